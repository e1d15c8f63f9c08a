//! Both kNN backends against the brute-force oracle, exactly: same indices,
//! same squared distances, same order, on seeded clouds chosen to break
//! inexact searches (ties, duplicates, far queries, k beyond n).

use glam::DVec3;
use scanmesh::spatial::{
    brute_knn, build_index, GridIndex, IndexError, KdIndex, KnnBackend, KnnIndex, Neighbour,
};
use scanmesh::synth::Rng;

/// The draws these tests need on top of the project's seeded generator.
trait Draws {
    fn index(&mut self, n: usize) -> usize;
    fn vec3(&mut self, lo: f64, hi: f64) -> DVec3;
}

impl Draws for Rng {
    fn index(&mut self, n: usize) -> usize {
        self.below(n as u64) as usize
    }
    fn vec3(&mut self, lo: f64, hi: f64) -> DVec3 {
        DVec3::new(self.range(lo, hi), self.range(lo, hi), self.range(lo, hi))
    }
}

fn uniform_cube(rng: &mut Rng, n: usize) -> Vec<DVec3> {
    (0..n).map(|_| rng.vec3(-1.0, 1.0)).collect()
}

fn clustered(rng: &mut Rng, n: usize) -> Vec<DVec3> {
    let centres: Vec<DVec3> = (0..5).map(|_| rng.vec3(-50.0, 50.0)).collect();
    (0..n)
        .map(|_| {
            let c = centres[rng.index(centres.len())];
            let spread = if rng.uniform() < 0.5 { 0.01 } else { 1.0 };
            c + rng.vec3(-spread, spread)
        })
        .collect()
}

/// Noisy unit sphere at UTM-like offsets.
fn sphere_surface(rng: &mut Rng, n: usize) -> Vec<DVec3> {
    let offset = DVec3::new(5.0e5, 4.2e6, 120.0);
    (0..n)
        .map(|_| {
            let z = rng.range(-1.0, 1.0);
            let phi = rng.range(0.0, std::f64::consts::TAU);
            let r = (1.0 - z * z).sqrt();
            let radius = 1.0 + rng.range(-1e-3, 1e-3);
            offset + radius * DVec3::new(r * phi.cos(), r * phi.sin(), z)
        })
        .collect()
}

/// An integer lattice: every point has many exactly equidistant neighbours.
fn lattice(rng: &mut Rng, n: usize) -> Vec<DVec3> {
    let side = (n as f64).cbrt().ceil() as i64;
    let step = [0.5, 1.0, 0.25][rng.index(3)];
    let mut pts = Vec::new();
    for z in 0..side {
        for y in 0..side {
            for x in 0..side {
                pts.push(DVec3::new(x as f64, y as f64, z as f64) * step);
            }
        }
    }
    pts.truncate(n);
    pts
}

/// A few locations repeated many times, plus some scatter.
fn duplicates(rng: &mut Rng, n: usize) -> Vec<DVec3> {
    let spots: Vec<DVec3> = (0..4).map(|_| rng.vec3(-2.0, 2.0)).collect();
    (0..n)
        .map(|i| {
            if i % 7 == 0 {
                rng.vec3(-2.0, 2.0)
            } else {
                spots[rng.index(spots.len())]
            }
        })
        .collect()
}

/// Unique tie keys in shuffled order, so tie order differs from index order.
fn shuffled_ties(rng: &mut Rng, n: usize) -> Vec<u64> {
    let mut tie: Vec<u64> = (0..n as u64).map(|i| i * 3 + 1000).collect();
    for i in (1..n).rev() {
        tie.swap(i, rng.index(i + 1));
    }
    tie
}

/// Queries: every data point (with and without excluding itself), random
/// points around the data, and points far outside it.
fn check_all(name: &str, seed: u64, points: &[DVec3], index: &dyn KnnIndex, k: usize, tie: &[u64]) {
    let mut rng = Rng::new(seed ^ 0xABCD);
    let mut out = vec![
        Neighbour {
            dist2: -1.0,
            index: 7
        };
        3
    ];
    let check = |q: DVec3, exclude: Option<u32>, out: &mut Vec<Neighbour>| {
        index.knn(q, k, exclude, out);
        let want = brute_knn(points, tie, q, k, exclude);
        assert_eq!(
            *out, want,
            "{name}: seed {seed}, k {k}, query {q:?}, exclude {exclude:?}"
        );
    };
    for (i, p) in points.iter().enumerate() {
        check(*p, Some(i as u32), &mut out);
        if i % 3 == 0 {
            check(*p, None, &mut out);
        }
    }
    let (lo, hi) = bounds(points);
    let size = (hi - lo).max_element().max(1.0);
    for _ in 0..100 {
        let t = DVec3::new(
            rng.range(-0.3, 1.3),
            rng.range(-0.3, 1.3),
            rng.range(-0.3, 1.3),
        );
        check(lo + t * (hi - lo), None, &mut out);
    }
    for scale in [3.0, 1e3, 1e9] {
        let dir = rng.vec3(-1.0, 1.0).normalize_or(DVec3::X);
        check(lo + dir * size * scale, None, &mut out);
    }
}

fn bounds(points: &[DVec3]) -> (DVec3, DVec3) {
    points.iter().fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    )
}

/// Every backend, including grids with extreme cell sizes, on one cloud.
fn check_backends(name: &str, seed: u64, points: &[DVec3], ks: &[usize]) {
    let mut rng = Rng::new(seed);
    let tie = shuffled_ties(&mut rng, points.len());
    let (lo, hi) = bounds(points);
    let size = (hi - lo).max_element().max(1e-9);
    let grid_auto = GridIndex::new(points, &tie).expect("grid");
    let grid_fine = GridIndex::with_cell(points, &tie, size * 0.02).expect("fine grid");
    let grid_tiny = GridIndex::with_cell(points, &tie, size * 1e-4).expect("tiny grid");
    let grid_coarse = GridIndex::with_cell(points, &tie, size * 10.0).expect("coarse grid");
    let kd = KdIndex::new(points, &tie).expect("kd-tree");
    let indexes: [(&str, &dyn KnnIndex); 5] = [
        ("grid auto", &grid_auto),
        ("grid fine", &grid_fine),
        ("grid tiny", &grid_tiny),
        ("grid coarse", &grid_coarse),
        ("kd", &kd),
    ];
    for (backend, index) in indexes {
        assert_eq!(index.len(), points.len());
        for &k in ks {
            check_all(&format!("{name}/{backend}"), seed, points, index, k, &tie);
        }
    }
}

#[test]
fn uniform_cube_matches_oracle() {
    for seed in 1..4 {
        let pts = uniform_cube(&mut Rng::new(seed), 1500);
        check_backends("uniform cube", seed, &pts, &[1, 12]);
    }
}

#[test]
fn clustered_matches_oracle() {
    for seed in 10..13 {
        let pts = clustered(&mut Rng::new(seed), 1500);
        check_backends("clustered", seed, &pts, &[8, 30]);
    }
}

#[test]
fn surface_at_utm_offset_matches_oracle() {
    for seed in 20..23 {
        let pts = sphere_surface(&mut Rng::new(seed), 2000);
        check_backends("sphere", seed, &pts, &[12]);
    }
}

#[test]
fn lattice_ties_match_oracle() {
    for seed in 30..32 {
        let pts = lattice(&mut Rng::new(seed), 1000);
        check_backends("lattice", seed, &pts, &[1, 7, 19]);
    }
}

#[test]
fn many_duplicates_match_oracle() {
    for seed in 40..43 {
        let pts = duplicates(&mut Rng::new(seed), 700);
        check_backends("duplicates", seed, &pts, &[3, 12, 200]);
    }
}

#[test]
fn k_beyond_n_returns_everything_in_order() {
    for seed in 50..53 {
        let pts = uniform_cube(&mut Rng::new(seed), 9);
        check_backends("tiny", seed, &pts, &[8, 9, 10, 100]);
    }
}

#[test]
fn single_point_and_single_location() {
    check_backends("one point", 60, &[DVec3::new(3.0, -2.0, 1.0)], &[1, 2]);
    check_backends("one location", 61, &[DVec3::splat(0.5); 40], &[1, 12, 40]);
}

#[test]
fn empty_index_and_zero_k_give_nothing() {
    for backend in [KnnBackend::Grid, KnnBackend::KdTree] {
        let index = build_index(backend, &[], &[]).expect("empty index");
        let mut out = vec![Neighbour {
            dist2: 0.0,
            index: 0,
        }];
        index.knn(DVec3::ZERO, 5, None, &mut out);
        assert!(out.is_empty() && index.is_empty());
        let pts = [DVec3::ZERO, DVec3::X];
        let index = build_index(backend, &pts, &[0, 1]).expect("index");
        index.knn(DVec3::ZERO, 0, None, &mut out);
        assert!(out.is_empty());
    }
}

#[test]
fn bad_input_is_an_error() {
    let pts = [DVec3::ZERO, DVec3::X];
    for backend in [KnnBackend::Grid, KnnBackend::KdTree] {
        let err = build_index(backend, &pts, &[0]).err();
        assert_eq!(
            err,
            Some(IndexError::TieLengthMismatch { points: 2, ties: 1 })
        );
    }
    for cell in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        assert!(matches!(
            GridIndex::with_cell(&pts, &[0, 1], cell),
            Err(IndexError::BadCellSize { .. })
        ));
    }
}

#[test]
fn auto_cell_holds_a_few_points_on_a_surface() {
    let pts = sphere_surface(&mut Rng::new(70), 20_000);
    let tie: Vec<u64> = (0..pts.len() as u64).collect();
    let grid = GridIndex::new(&pts, &tie).expect("grid");
    let mean = pts.len() as f64 / grid.occupied_cells() as f64;
    assert!((1.0..=16.0).contains(&mean), "mean occupancy {mean}");
}

/// Many small quantised clouds (exact ties everywhere, points on cell
/// boundaries) with random cell sizes, k and queries.
#[test]
fn small_quantised_clouds_with_random_cells_match_oracle() {
    for seed in 100..400u64 {
        let mut rng = Rng::new(seed);
        let n = 1 + rng.index(80);
        let quantum = [0.25, 0.5, 1.0][rng.index(3)];
        let pts: Vec<DVec3> = (0..n)
            .map(|_| (rng.vec3(0.0, 6.0) / quantum).round() * quantum)
            .collect();
        let tie = shuffled_ties(&mut rng, n);
        let cell = [1e-3, 0.25, 0.5, 0.7, 1.0, 3.0, 50.0][rng.index(7)];
        let grid = GridIndex::with_cell(&pts, &tie, cell).expect("grid");
        let kd = KdIndex::new(&pts, &tie).expect("kd-tree");
        let mut out = Vec::new();
        for _ in 0..40 {
            let k = 1 + rng.index(n + 3);
            let q = (rng.vec3(-2.0, 8.0) / quantum).round() * quantum;
            let exclude = (rng.uniform() < 0.5).then(|| rng.index(n) as u32);
            let want = brute_knn(&pts, &tie, q, k, exclude);
            for (name, index) in [("grid", &grid as &dyn KnnIndex), ("kd", &kd)] {
                index.knn(q, k, exclude, &mut out);
                assert_eq!(
                    out, want,
                    "{name}: seed {seed}, cell {cell}, k {k}, q {q:?}, exclude {exclude:?}"
                );
            }
        }
    }
}

/// `points` with `n` exact copies of every `stride`-th one appended: ties
/// the tie keys must decide.
fn with_copies(mut points: Vec<DVec3>, n: usize, stride: usize) -> Vec<DVec3> {
    for i in 0..n {
        points.push(points[i * stride]);
    }
    points
}

#[test]
fn nearest_from_any_hint_is_the_nearest() {
    for seed in [21u64, 22] {
        let mut rng = Rng::new(seed);
        let points = with_copies(clustered(&mut rng, 2000), 50, 7);
        let tie: Vec<u64> = (0..points.len() as u64).rev().collect();
        // Cells of several sizes: the signed distance sizes its grid to the
        // lattice, far from the automatic size.
        for cell in [0.01, 0.05, 0.3] {
            let grid = GridIndex::with_cell(&points, &tie, cell).expect("grid");
            let mut got = Vec::new();
            for _ in 0..300 {
                let q = rng.vec3(-1.2, 1.2);
                let h = rng.index(points.len()) as u32;
                grid.nearest_from(q, (h, points[h as usize]), &mut got);
                let want = brute_knn(&points, &tie, q, 1, None);
                assert_eq!(got, want, "seed {seed} cell {cell} query {q:?} hint {h}");
            }
        }
    }
}

/// The k nearest with the search bounded by an earlier answer: whatever
/// `out` holds on entry (a nearby query's answer, a far one's, too few
/// points, indices past the index), the answer is the oracle's.
#[test]
fn knn_near_any_earlier_answer_is_the_oracles() {
    for seed in [31u64, 32] {
        let mut rng = Rng::new(seed);
        let points = with_copies(sphere_surface(&mut rng, 3000), 40, 11);
        let tie: Vec<u64> = (0..points.len() as u64).rev().collect();
        for cell in [0.02, 0.1, 0.5] {
            let grid = GridIndex::with_cell(&points, &tie, cell).expect("grid");
            let mut out = Vec::new();
            // The sphere lies at a UTM-like offset: the origin is far.
            let far = DVec3::ZERO;
            for i in 0..400 {
                let k = [1, 5, 16, 40][i % 4];
                let q = points[rng.index(points.len())] + rng.vec3(-0.05, 0.05);
                match i % 5 {
                    // A stale answer from far away.
                    3 => grid.knn_near(far + rng.vec3(-2.0, 2.0), 40, &mut out),
                    // Indices past the index.
                    4 => out.iter_mut().for_each(|n| n.index = u32::MAX - n.index),
                    _ => {}
                }
                grid.knn_near(q, k, &mut out);
                let want = brute_knn(&points, &tie, q, k, None);
                assert_eq!(out, want, "seed {seed} cell {cell} query {i} k {k}");
            }
        }
    }
}
