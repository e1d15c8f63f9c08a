//! R*-tree kNN (hollow sphere and best-first) against a brute-force oracle,
//! and topological neighbours by mean reverse shift (paper 3) on analytic
//! sheets: uniform grids, a 20:1 density step, noisy samples; margins
//! (`reach`) and thread-count determinism.

use glam::DVec3;
use scanmesh::normals::pca::fit_plane_points;
use scanmesh::spatial::rtree::{RTreeError, RTreeIndex};
use scanmesh::spatial::topological::{
    all_topological, topological_neighbours, TopoError, TopoParams, TopoResult, TopoScratch,
};
use scanmesh::spatial::{KnnIndex, Neighbour};
use scanmesh::synth::Rng;

/// Tie keys that are a scrambled permutation, so tie order != index order.
fn scrambled_ties(n: usize) -> Vec<u64> {
    (0..n as u64)
        .map(|i| (i * 7919 + 13) % (n as u64).max(1) * 1000 + i)
        .collect()
}

fn brute_knn(points: &[DVec3], tie: &[u64], q: DVec3, k: usize, ex: Option<u32>) -> Vec<Neighbour> {
    let mut all: Vec<Neighbour> = (0..points.len() as u32)
        .filter(|&i| Some(i) != ex)
        .map(|i| Neighbour {
            dist2: (points[i as usize] - q).length_squared(),
            index: i,
        })
        .collect();
    all.sort_by(|a, b| {
        (a.dist2, tie[a.index as usize], a.index)
            .partial_cmp(&(b.dist2, tie[b.index as usize], b.index))
            .unwrap()
    });
    all.truncate(k);
    all
}

/// Clouds with plenty of exact ties: random, integer lattice, duplicates.
fn tie_clouds(seed: u64) -> Vec<(&'static str, Vec<DVec3>)> {
    let mut rng = Rng::new(seed);
    let random = (0..700)
        .map(|_| DVec3::new(rng.range(-5., 5.), rng.range(-5., 5.), rng.range(-1., 1.)))
        .collect();
    let lattice: Vec<DVec3> = (0..600)
        .map(|_| {
            DVec3::new(
                rng.range(0., 9.).floor(),
                rng.range(0., 9.).floor(),
                rng.range(0., 3.).floor(),
            )
        })
        .collect();
    let mut dups: Vec<DVec3> = (0..150)
        .map(|_| DVec3::new(rng.range(0., 4.), rng.range(0., 4.), 0.))
        .collect();
    dups.extend_from_within(..);
    dups.extend_from_within(..100);
    let same = vec![DVec3::new(1.5, -2.0, 3.0); 40];
    vec![
        ("random", random),
        ("lattice", lattice),
        ("duplicates", dups),
        ("identical", same),
    ]
}

#[test]
fn rtree_knn_equals_brute_force_with_ties_and_duplicates() {
    for seed in [1u64, 2, 3, 77] {
        for (name, points) in tie_clouds(seed) {
            let tie = scrambled_ties(points.len());
            let index = RTreeIndex::new(&points, &tie).unwrap();
            let mut rng = Rng::new(seed ^ 0xABCD);
            let mut got = Vec::new();
            for trial in 0..120 {
                let i = (rng.next_u64() % points.len() as u64) as u32;
                let (q, ex) = match trial % 3 {
                    0 => (points[i as usize], Some(i)),
                    1 => (points[i as usize], None),
                    _ => (
                        DVec3::new(rng.range(-8., 12.), rng.range(-8., 12.), rng.range(-3., 5.))
                            .round(),
                        None,
                    ),
                };
                for k in [1, 4, 15, 33, points.len() + 3] {
                    let want = brute_knn(&points, &tie, q, k, ex);
                    index.knn_hollow(q, k, ex, &mut got);
                    assert_eq!(
                        got, want,
                        "hollow: seed {seed} cloud {name} q {q} k {k} ex {ex:?}"
                    );
                    index.knn_best_first(q, k, ex, &mut got);
                    assert_eq!(
                        got, want,
                        "best-first: seed {seed} cloud {name} q {q} k {k} ex {ex:?}"
                    );
                    index.knn(q, k, ex, &mut got);
                    assert_eq!(
                        got, want,
                        "KnnIndex: seed {seed} cloud {name} q {q} k {k} ex {ex:?}"
                    );
                }
            }
        }
    }
}

#[test]
fn rtree_rejects_bad_input_and_handles_degenerate_queries() {
    let points = vec![DVec3::ZERO, DVec3::X, DVec3::new(f64::NAN, 0., 0.)];
    assert_eq!(
        RTreeIndex::new(&points, &[0, 1]).err(),
        Some(RTreeError::LengthMismatch { points: 3, ties: 2 })
    );
    assert_eq!(
        RTreeIndex::new(&points, &[0, 1, 2]).err(),
        Some(RTreeError::NonFinite { index: 2 })
    );
    let empty = RTreeIndex::new(&[], &[]).unwrap();
    let mut out = vec![Neighbour {
        dist2: 1.0,
        index: 9,
    }];
    empty.knn_hollow(DVec3::ZERO, 5, None, &mut out);
    assert!(out.is_empty());
    let good = RTreeIndex::new(&points[..2], &[5, 4]).unwrap();
    good.knn_hollow(DVec3::splat(f64::NAN), 2, None, &mut out);
    assert!(out.is_empty(), "a NaN query has no neighbours");
    good.knn_hollow(DVec3::splat(1e300), 2, Some(7), &mut out);
    assert_eq!(
        out.len(),
        2,
        "far query and out-of-range exclude still answer"
    );
}

#[test]
fn topological_rejects_mismatched_inputs() {
    let points = vec![DVec3::ZERO, DVec3::X, DVec3::Y];
    let tie = [0, 1, 2];
    let index = RTreeIndex::new(&points, &tie).unwrap();
    let params = TopoParams::default();
    let mut s = TopoScratch::new();
    let err = topological_neighbours(&index, &points[..2], &tie, 0, &params, &mut s);
    assert_eq!(
        err.err(),
        Some(TopoError::IndexMismatch {
            index: 3,
            points: 2,
            ties: 3
        })
    );
    let err = topological_neighbours(&index, &points, &tie, 3, &params, &mut s);
    assert_eq!(
        err.err(),
        Some(TopoError::PointOutOfRange { point: 3, len: 3 })
    );
    let r = topological_neighbours(&index, &points, &tie, 0, &params, &mut s).unwrap();
    assert_eq!(r.neighbours.len(), 2, "fewer points than k: all of them");
    assert!(r.reach.is_infinite(), "a short kNN needed every point");
}

fn centroid_offset_ratio(points: &[DVec3], o: DVec3, hood: &[Neighbour]) -> f64 {
    let c = hood.iter().map(|n| points[n.index as usize]).sum::<DVec3>() / hood.len() as f64;
    let radius = hood.iter().map(|n| n.dist2).fold(0.0, f64::max).sqrt();
    (c - o).length() / radius
}

fn knn_of(index: &RTreeIndex, points: &[DVec3], i: usize, k: usize) -> Vec<Neighbour> {
    let mut out = Vec::new();
    index.knn(points[i], k, Some(i as u32), &mut out);
    out
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

#[test]
fn uniform_grid_topological_contains_knn_and_is_centred() {
    let n = 40;
    let points: Vec<DVec3> = (0..n * n)
        .map(|i| DVec3::new((i % n) as f64, (i / n) as f64, 0.0))
        .collect();
    let tie: Vec<u64> = (0..points.len() as u64).collect();
    let index = RTreeIndex::new(&points, &tie).unwrap();
    let params = TopoParams::default();
    let all = all_topological(&index, &points, &tie, &params).unwrap();
    let inner = |p: DVec3| p.x >= 8.0 && p.x < 32.0 && p.y >= 8.0 && p.y < 32.0;
    let (mut topo, mut knn) = (Vec::new(), Vec::new());
    for (i, r) in all.iter().enumerate().filter(|(i, _)| inner(points[*i])) {
        let plain = knn_of(&index, &points, i, params.k);
        assert!(
            plain.iter().all(|n| r.neighbours.contains(n)),
            "T must contain kNN at point {i}"
        );
        topo.push(centroid_offset_ratio(&points, points[i], &r.neighbours));
        knn.push(centroid_offset_ratio(&points, points[i], &plain));
    }
    let (mt, mk) = (
        topo.iter().sum::<f64>() / topo.len() as f64,
        knn.iter().sum::<f64>() / knn.len() as f64,
    );
    println!("uniform grid: mean centroid offset / radius: topological {mt:.4}, kNN {mk:.4}");
    assert!(
        mt < 0.1 && mt <= mk + 1e-12,
        "offset topological {mt}, kNN {mk}"
    );
}

/// Jitter of the sampling grids, in spacings.
const JITTER: f64 = 0.3;
/// Spacing of the sparse side (the dense side's is 1): density ratio 20.25.
const SPARSE: f64 = 4.5;

/// A sheet `z = height(x, y)`: jittered grid of spacing 1 for x < 0, of
/// spacing [`SPARSE`] for x >= 0.
fn step_sheet(seed: u64, height: impl Fn(f64, f64) -> f64) -> Vec<DVec3> {
    let mut rng = Rng::new(seed);
    let mut points = Vec::new();
    for (x0, x1, s) in [(-40.0, 0.0, 1.0), (0.0, 90.0, SPARSE)] {
        let (nx, ny) = (((x1 - x0) / s) as usize, (120.0 / s) as usize);
        for ix in 0..nx {
            for iy in 0..ny {
                let x = x0 + (ix as f64 + 0.5 + rng.range(-JITTER, JITTER)) * s;
                let y = (iy as f64 + 0.5 + rng.range(-JITTER, JITTER)) * s;
                points.push(DVec3::new(x, y, height(x, y)));
            }
        }
    }
    points
}

/// The points near the step (within 3 sparse spacings) and far from the
/// sheet's outer borders.
fn near_step(points: &[DVec3]) -> Vec<usize> {
    (0..points.len())
        .filter(|&i| points[i].x.abs() < 3.0 * SPARSE && points[i].y > 30.0 && points[i].y < 90.0)
        .collect()
}

const CURVE_RADIUS: f64 = 40.0;

fn paraboloid(x: f64, y: f64) -> f64 {
    (x * x + (y - 60.0) * (y - 60.0)) / (2.0 * CURVE_RADIUS)
}

fn paraboloid_normal(p: DVec3) -> DVec3 {
    DVec3::new(-p.x / CURVE_RADIUS, -(p.y - 60.0) / CURVE_RADIUS, 1.0).normalize()
}

/// PCA normal of O and its neighbourhood: the library's tangent plane
/// (centred, f64, Jacobi), which tests/pca_eigen.rs checks on its own.
fn pca_normal(points: &[DVec3], o: DVec3, hood: &[Neighbour]) -> DVec3 {
    let pts: Vec<DVec3> = std::iter::once(o)
        .chain(hood.iter().map(|n| points[n.index as usize]))
        .collect();
    fit_plane_points(&pts)
        .expect("non-degenerate neighbourhood")
        .normal
}

fn angle_deg(a: DVec3, b: DVec3) -> f64 {
    a.normalize()
        .dot(b.normalize())
        .abs()
        .min(1.0)
        .acos()
        .to_degrees()
}

/// Mean centroid offset ratio over the points of `sel` on one side of the
/// step (or both), for topological T and for plain kNN.
struct OffsetStats {
    topo: Vec<f64>,
    knn: Vec<f64>,
    dense: Vec<bool>,
}

impl OffsetStats {
    fn ratio(&self, side: Option<bool>) -> (f64, f64, f64) {
        let pick = |v: &[f64]| {
            let s: Vec<f64> = v
                .iter()
                .zip(&self.dense)
                .filter(|(_, d)| side.is_none_or(|w| **d == w))
                .map(|(x, _)| *x)
                .collect();
            s.iter().sum::<f64>() / s.len() as f64
        };
        let (t, k) = (pick(&self.topo), pick(&self.knn));
        (t, k, k / t)
    }
}

/// The key figure: near a 20:1 density step, kNN crowds to the
/// dense side; topological neighbours surround the point. The 2x target is
/// asserted on the sparse side, where the step's effect lives; pooled with
/// the dense side (20x more points, whose offsets mostly come from the
/// sampling jitter) the method reaches about 2x, so the pooled bound is 1.5x.
#[test]
fn density_step_topological_is_centred_and_gives_better_normals() {
    let seed = 20;
    let k = TopoParams::default().k;
    for (sheet, curved) in [("flat", false), ("paraboloid", true)] {
        let points = step_sheet(seed, |x, y| if curved { paraboloid(x, y) } else { 0.0 });
        let tie: Vec<u64> = (0..points.len() as u64).collect();
        let index = RTreeIndex::new(&points, &tie).unwrap();
        let all = all_topological(&index, &points, &tie, &TopoParams::default()).unwrap();
        let mut stats = OffsetStats {
            topo: vec![],
            knn: vec![],
            dense: vec![],
        };
        let (mut err_t, mut err_k) = (vec![], vec![]);
        for i in near_step(&points) {
            let (o, plain) = (points[i], knn_of(&index, &points, i, k));
            stats
                .topo
                .push(centroid_offset_ratio(&points, o, &all[i].neighbours));
            stats.knn.push(centroid_offset_ratio(&points, o, &plain));
            stats.dense.push(o.x < 0.0);
            let truth = if curved {
                paraboloid_normal(o)
            } else {
                DVec3::Z
            };
            err_t.push(angle_deg(pca_normal(&points, o, &all[i].neighbours), truth));
            err_k.push(angle_deg(pca_normal(&points, o, &plain), truth));
        }
        println!(
            "{sheet} step sheet, seed {seed}, {} points within 3 sparse spacings of the step:",
            stats.topo.len()
        );
        for (name, side) in [
            ("both sides", None),
            ("sparse side", Some(false)),
            ("dense side", Some(true)),
        ] {
            let (t, kn, r) = stats.ratio(side);
            println!("  {name}: mean |centroid - O| / radius: topological {t:.4}, kNN {kn:.4}, kNN/topological {r:.2}");
        }
        let (et, ek) = (median(err_t), median(err_k));
        if curved {
            println!("  median normal error vs truth: topological {et:.3} deg, kNN {ek:.3} deg");
        }
        let (sparse, pooled) = (stats.ratio(Some(false)).2, stats.ratio(None).2);
        assert!(
            sparse >= 2.0,
            "seed {seed} {sheet}: sparse-side offset ratio kNN/topological {sparse}"
        );
        assert!(
            pooled >= 1.5,
            "seed {seed} {sheet}: pooled offset ratio kNN/topological {pooled}"
        );
        if curved {
            assert!(
                et < ek,
                "seed {seed}: normal error topological {et} vs kNN {ek}"
            );
        }
    }
}

fn histogram(results: &[&TopoResult]) -> Vec<usize> {
    let mut h = vec![0; 12];
    for r in results {
        h[(r.iterations as usize).min(11)] += 1;
    }
    h
}

fn check_iteration_statistics(name: &str, points: &[DVec3]) {
    let tie: Vec<u64> = (0..points.len() as u64).collect();
    let index = RTreeIndex::new(points, &tie).unwrap();
    let params = TopoParams::default();
    let all = all_topological(&index, points, &tie, &params).unwrap();
    let all: Vec<&TopoResult> = all.iter().collect();
    let its = median(all.iter().map(|r| r.iterations as f64).collect());
    let sized = all
        .iter()
        .filter(|r| (params.k..=3 * params.k).contains(&r.neighbours.len()));
    let frac = sized.count() as f64 / all.len() as f64;
    let capped = all.iter().filter(|r| r.hit_cap).count();
    let largest = all.iter().map(|r| r.neighbours.len()).max().unwrap_or(0);
    println!(
        "{name}: {} points (borders included), iteration histogram {:?}, median {its}, \
         |T| in [k,3k] for {:.1} % (largest {largest}), capped {capped}",
        all.len(),
        histogram(&all),
        100.0 * frac
    );
    assert!(its <= 4.0, "{name}: median iterations {its}");
    assert!(frac >= 0.95, "{name}: |T| in [k, 3k] for only {frac}");
}

#[test]
fn iteration_statistics_on_noisy_uniform_and_step_clouds() {
    let seed = 4;
    let mut rng = Rng::new(seed);
    let noisy: Vec<DVec3> = (0..4000)
        .map(|_| {
            DVec3::new(
                rng.range(0., 60.),
                rng.range(0., 60.),
                rng.range(-0.05, 0.05),
            )
        })
        .collect();
    println!("seed {seed}");
    check_iteration_statistics("noisy uniform", &noisy);
    let step = step_sheet(seed, paraboloid);
    check_iteration_statistics("density step", &step);
}

#[test]
fn reach_is_a_sufficient_margin() {
    let seed = 9;
    let points = step_sheet(seed, paraboloid);
    let tie: Vec<u64> = (0..points.len() as u64).map(|i| i * 3 + 1).collect();
    let index = RTreeIndex::new(&points, &tie).unwrap();
    let params = TopoParams::default();
    let mut scratch = TopoScratch::new();
    for &i in near_step(&points).iter().step_by(7) {
        let full =
            topological_neighbours(&index, &points, &tie, i as u32, &params, &mut scratch).unwrap();
        let o = points[i];
        let kept: Vec<usize> = (0..points.len())
            .filter(|&j| (points[j] - o).length() <= full.reach)
            .collect();
        let sub_points: Vec<DVec3> = kept.iter().map(|&j| points[j]).collect();
        let sub_tie: Vec<u64> = kept.iter().map(|&j| tie[j]).collect();
        let sub_index = RTreeIndex::new(&sub_points, &sub_tie).unwrap();
        let local = kept.iter().position(|&j| j == i).unwrap() as u32;
        let tile = topological_neighbours(
            &sub_index,
            &sub_points,
            &sub_tie,
            local,
            &params,
            &mut scratch,
        )
        .unwrap();
        let back: Vec<(f64, u32)> = tile
            .neighbours
            .iter()
            .map(|n| (n.dist2, kept[n.index as usize] as u32))
            .collect();
        let want: Vec<(f64, u32)> = full.neighbours.iter().map(|n| (n.dist2, n.index)).collect();
        assert_eq!(
            back, want,
            "seed {seed} point {i}: tile of radius reach {} differs",
            full.reach
        );
        assert_eq!(
            (tile.iterations, tile.hit_cap),
            (full.iterations, full.hit_cap)
        );
    }
}

#[test]
fn same_result_with_one_and_two_threads() {
    let seed = 31;
    let points = step_sheet(seed, paraboloid);
    let tie = scrambled_ties(points.len());
    let index = RTreeIndex::new(&points, &tie).unwrap();
    let params = TopoParams::default();
    let run = |threads| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| all_topological(&index, &points, &tie, &params).unwrap())
    };
    let (one, two) = (run(1), run(2));
    assert_eq!(one.len(), points.len());
    for (i, (a, b)) in one.iter().zip(&two).enumerate() {
        assert_eq!(a, b, "seed {seed} point {i}");
        assert_eq!(
            a.reach.to_bits(),
            b.reach.to_bits(),
            "seed {seed} point {i}"
        );
    }
}
