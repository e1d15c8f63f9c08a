//! The triangulation against a brute-force oracle (every 4-subset whose
//! perturbed circumsphere is empty) on small seeded inputs, and the
//! degenerate inputs of issue 18: quantised grids, cospherical lattices,
//! planar and linear clouds, repeated points.

use super::predicates::{in_sphere_perturbed, orient};
use super::{sanity_check, Delaunay, DelaunayError, INFINITE};
use crate::rng::Rng;
use glam::DVec3;

fn ids(n: usize) -> Vec<u64> {
    (0..n as u64).collect()
}

/// Finite cells as sorted vertex sets, sorted.
fn finite_cells(d: &Delaunay) -> Vec<[u32; 4]> {
    let mut out: Vec<[u32; 4]> = d
        .cell_slots()
        .iter()
        .filter(|c| !c.is_free() && !c.v.contains(&INFINITE))
        .map(|c| {
            let mut v = c.v.map(|v| d.input_index(v));
            v.sort_unstable();
            v
        })
        .collect();
    out.sort_unstable();
    out
}

/// Every 4-subset of non-coplanar points whose perturbed sphere holds no
/// other point.
fn brute_force(points: &[DVec3], ranks: &[u64]) -> Vec<[u32; 4]> {
    let n = points.len();
    let mut out = Vec::new();
    for a in 0..n {
        for b in a + 1..n {
            for c in b + 1..n {
                for e in c + 1..n {
                    let mut v = [a, b, c, e];
                    let o = orient(points[a], points[b], points[c], points[e]);
                    if o == 0.0 {
                        continue;
                    }
                    if o < 0.0 {
                        v.swap(0, 1);
                    }
                    let pos = v.map(|i| points[i]);
                    let rk = v.map(|i| ranks[i]);
                    let empty = (0..n)
                        .filter(|m| !v.contains(m))
                        .all(|m| !in_sphere_perturbed(pos, || rk, points[m], ranks[m]));
                    if empty {
                        out.push([a as u32, b as u32, c as u32, e as u32]);
                    }
                }
            }
        }
    }
    out
}

fn check_against_oracle(points: &[DVec3], ranks: &[u64], what: &str) {
    let d = Delaunay::new(points, ranks).unwrap_or_else(|e| panic!("{what}: {e}"));
    sanity_check(&d).unwrap_or_else(|e| panic!("{what}: {e}"));
    assert_eq!(finite_cells(&d), brute_force(points, ranks), "{what}");
}

#[test]
fn random_points_match_the_oracle() {
    for seed in 0..20 {
        let mut rng = Rng::new(seed);
        let points: Vec<DVec3> = (0..28)
            .map(|_| DVec3::new(rng.uniform(), rng.uniform(), rng.uniform()))
            .collect();
        check_against_oracle(&points, &ids(points.len()), &format!("seed {seed}"));
    }
}

#[test]
fn cube_lattice_matches_the_oracle_under_any_ranks() {
    // Every unit cube's eight corners are cospherical and every face's four
    // corners cocircular: the answer is decided by the ranks alone.
    let mut points = Vec::new();
    for x in 0..3 {
        for y in 0..3 {
            for z in 0..3 {
                points.push(DVec3::new(x as f64, y as f64, z as f64));
            }
        }
    }
    for seed in 0..6 {
        let mut rng = Rng::new(seed);
        let mut ranks = ids(points.len());
        for i in (1..ranks.len()).rev() {
            ranks.swap(i, rng.below(i as u64 + 1) as usize);
        }
        check_against_oracle(&points, &ranks, &format!("lattice ranks seed {seed}"));
    }
}

#[test]
fn points_on_a_hull_plane_match_the_oracle() {
    // Two square grids on parallel planes: the hull faces are cocircular
    // squares, so insertions on a hull plane take the coplanar circle test.
    let mut points = Vec::new();
    for x in 0..4 {
        for y in 0..4 {
            points.push(DVec3::new(x as f64, y as f64, 0.0));
            points.push(DVec3::new(x as f64 + 0.5, y as f64, 1.0));
        }
    }
    check_against_oracle(&points, &ids(points.len()), "two planes");
}

/// Integer points with `x^2 + y^2 + z^2 = r2`, all on one sphere exactly.
fn integer_sphere(r2: i64) -> Vec<DVec3> {
    let r = (r2 as f64).sqrt() as i64 + 1;
    let mut out = Vec::new();
    for x in -r..=r {
        for y in -r..=r {
            let z2 = r2 - x * x - y * y;
            if z2 < 0 {
                continue;
            }
            let z = (z2 as f64).sqrt().round() as i64;
            if z * z == z2 {
                out.push(DVec3::new(x as f64, y as f64, z as f64));
                if z != 0 {
                    out.push(DVec3::new(x as f64, y as f64, -z as f64));
                }
            }
        }
    }
    out
}

#[test]
fn small_cospherical_set_matches_the_oracle() {
    let points = integer_sphere(50);
    assert!(points.len() > 40, "{}", points.len());
    let points = &points[..points.len().min(40)];
    check_against_oracle(points, &ids(points.len()), "sphere r2 50");
}

#[test]
fn ten_thousand_cospherical_points_triangulate() {
    let points = integer_sphere(5_000_006);
    // 22,272 points on the sphere; every other one, all still cospherical.
    let points: Vec<DVec3> = points.into_iter().step_by(2).take(10_000).collect();
    assert_eq!(points.len(), 10_000);
    let ranks = ids(points.len());
    let d = Delaunay::new(&points, &ranks).unwrap();
    sanity_check(&d).unwrap();
    assert_eq!(d.vertex_count(), 10_000);
}

#[test]
fn centimetre_grid_triangulates() {
    // LAS-like: x, y on a 1 cm grid, heights quantised to 1 cm.
    let mut points = Vec::new();
    for i in 0..400 {
        for j in 0..250 {
            let (x, y) = (i as f64 * 0.01, j as f64 * 0.01);
            let z = ((x * 3.0).sin() * 0.2 + y * 0.1) * 100.0;
            points.push(DVec3::new(x + 512_000.0, y + 4_200_000.0, z.round() * 0.01));
        }
    }
    assert_eq!(points.len(), 100_000);
    let ranks = ids(points.len());
    let d = Delaunay::new(&points, &ranks).unwrap();
    sanity_check(&d).unwrap();
    assert_eq!(d.vertex_count(), 100_000);
}

#[test]
fn degenerate_clouds_say_why() {
    let planar: Vec<DVec3> = (0..500)
        .map(|i| DVec3::new((i % 23) as f64 * 0.3, (i / 23) as f64 * 0.7, 2.0))
        .collect();
    let linear: Vec<DVec3> = (0..50).map(|i| DVec3::splat(i as f64)).collect();
    let same = vec![DVec3::new(0.1, 0.2, 0.3); 1000];
    let shape = |p: &[DVec3]| {
        let ranks = ids(p.len());
        match Delaunay::new(p, &ranks) {
            Err(DelaunayError::Degenerate { shape, .. }) => shape,
            Err(e) => panic!("{e}"),
            Ok(_) => panic!("a degenerate cloud triangulated"),
        }
    };
    assert_eq!(shape(&planar), "coplanar");
    assert_eq!(shape(&linear), "collinear");
    assert_eq!(shape(&same), "one point");
    let mut bad = planar.clone();
    bad[7].y = f64::NAN;
    let ranks = ids(bad.len());
    assert!(matches!(
        Delaunay::new(&bad, &ranks),
        Err(DelaunayError::NonFinite { index: 7 })
    ));
}

#[test]
fn repeated_points_are_left_out() {
    let mut points = vec![DVec3::new(0.1, 0.2, 0.3); 1000];
    points.extend([DVec3::X, DVec3::Y, DVec3::Z, DVec3::ONE]);
    // Ranks in reverse, so the kept copy is the last one.
    let ranks: Vec<u64> = (0..points.len() as u64).rev().collect();
    let d = Delaunay::new(&points, &ranks).unwrap();
    sanity_check(&d).unwrap();
    assert_eq!(d.vertex_count(), 5);
    assert_eq!(d.points().len() + d.duplicates().len(), points.len());
    assert_eq!(d.duplicates().len(), 999);
    assert!(d.duplicates().iter().all(|&(_, kept)| kept == 999));
}

#[test]
fn noisy_surface_sample_is_delaunay() {
    let scan =
        crate::synth::generate(&crate::synth::Shape::torus(1.0, 0.3), 20_000, 1e-3, 3).unwrap();
    let ranks = ids(scan.points.len());
    let d = Delaunay::new(&scan.points, &ranks).unwrap();
    sanity_check(&d).unwrap();
    assert_eq!(d.vertex_count(), 20_000);
}

/// The filtered `orient` has robust's exact sign, on random points and on
/// points rounded onto near-coplanar and exactly coplanar configurations.
#[test]
fn filtered_orient_has_the_exact_sign() {
    let c = |p: DVec3| robust::Coord3D {
        x: p.x,
        y: p.y,
        z: p.z,
    };
    let mut s = 0x9E37_79B9_7F4A_7C15u64;
    let mut r = move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    for k in 0..200_000 {
        let mut p = [DVec3::ZERO; 4];
        for q in &mut p {
            *q = DVec3::new(r(), r(), r()) * 1e-3 + DVec3::splat(0.1);
        }
        if k % 2 == 1 {
            // d on the plane of a, b, c up to rounding (or exactly: z = 0).
            let (u, v) = (r(), r());
            p[3] = p[0] + (p[1] - p[0]) * u + (p[2] - p[0]) * v;
            if k % 4 == 3 {
                for q in &mut p {
                    q.z = 0.25;
                }
            }
        }
        let exact = robust::orient3d(c(p[0]), c(p[1]), c(p[2]), c(p[3]));
        let got = orient(p[0], p[1], p[2], p[3]);
        assert_eq!(got.partial_cmp(&0.0), exact.partial_cmp(&0.0), "{p:?}");
    }
}
