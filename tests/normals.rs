//! Normals end to end: accuracy on analytic surfaces, consistent orientation,
//! tiled == untiled bit for bit, 1 thread == 2 threads, degenerate input.

mod common;

use common::{angle_deg, median, normals_of, normals_with};
use glam::DVec3;
use scanmesh::normals::{NormalParams, Orientation, FLAG_DEGENERATE, FLAG_UNORIENTED};
use scanmesh::pipeline::{MemoryBudget, RunOptions};
use scanmesh::spatial::KnnBackend;
use scanmesh::synth::{generate, Shape};

fn check_outward(shape: &Shape, n: usize, noise: f64, max_median_deg: f64) {
    let scan = generate(shape, n, noise, 7).expect("generate");
    let out = normals_of(&scan.points, u64::MAX, 2, &NormalParams::default());
    assert_eq!(out.report.degenerate, 0);
    let mut errs = Vec::new();
    let mut agree = 0;
    for (i, n) in out.normals.iter().enumerate() {
        let truth = scan.normals[i];
        errs.push(angle_deg(n.as_dvec3(), truth, true));
        agree += usize::from(n.as_dvec3().dot(truth) > 0.0);
    }
    let med = median(errs);
    assert!(
        med < max_median_deg,
        "{}: median angle error {med:.3} deg",
        shape.name()
    );
    assert_eq!(
        agree,
        n,
        "{}: {} of {n} normals point outward",
        shape.name(),
        agree
    );
}

#[test]
fn sphere_normals_are_radial_and_outward() {
    check_outward(&Shape::unit_sphere(), 20_000, 0.0, 1.0);
}

#[test]
fn torus_normals_are_accurate_and_outward() {
    check_outward(&Shape::torus(1.0, 0.3), 30_000, 0.0, 1.5);
}

#[test]
fn noisy_sphere_stays_oriented() {
    check_outward(&Shape::unit_sphere(), 20_000, 0.002, 5.0);
}

#[test]
fn tiled_equals_untiled_bit_for_bit() {
    let scan = generate(&Shape::torus(1.0, 0.3), 40_000, 0.001, 11).expect("generate");
    let params = NormalParams::default();
    let whole = normals_of(&scan.points, u64::MAX, 2, &params);
    let tiled = normals_of(&scan.points, 600, 2, &params);
    assert_eq!(whole.report.tiles, 1);
    assert!(
        tiled.report.tiles >= 64,
        "only {} tiles",
        tiled.report.tiles
    );
    assert!(
        whole.bytes == tiled.bytes,
        "tiled output differs from untiled"
    );
}

#[test]
fn one_thread_equals_two_threads() {
    let scan = generate(&Shape::unit_sphere(), 20_000, 0.001, 3).expect("generate");
    let params = NormalParams::default();
    let one = normals_of(&scan.points, 1500, 1, &params);
    let two = normals_of(&scan.points, 1500, 2, &params);
    assert!(
        one.bytes == two.bytes,
        "1-thread and 2-thread outputs differ"
    );
}

#[test]
fn grid_and_kdtree_give_the_same_normals() {
    let scan = generate(&Shape::torus(1.0, 0.3), 20_000, 0.001, 5).expect("generate");
    let kd = normals_of(&scan.points, 2000, 2, &NormalParams::default());
    let grid = normals_of(
        &scan.points,
        2000,
        2,
        &NormalParams {
            backend: KnnBackend::Grid,
            ..NormalParams::default()
        },
    );
    assert!(kd.bytes == grid.bytes);
}

#[test]
fn viewpoint_orientation_faces_the_scanner() {
    let scan = generate(&Shape::terrain(), 20_000, 0.0, 9).expect("generate");
    let view = DVec3::new(0.0, 0.0, 1000.0);
    let params = NormalParams {
        orientation: Orientation::Viewpoint(view),
        ..NormalParams::default()
    };
    let out = normals_of(&scan.points, 3000, 2, &params);
    for (i, n) in out.normals.iter().enumerate() {
        if out.flags[i] & FLAG_DEGENERATE == 0 {
            assert!(n.as_dvec3().dot(view - scan.points[i]) > 0.0, "point {i}");
        }
    }
}

#[test]
fn colinear_points_are_flagged_not_invented() {
    let points: Vec<DVec3> = (0..500)
        .map(|i| DVec3::new(i as f64 * 0.01, 2.0, 3.0))
        .collect();
    let out = normals_of(&points, u64::MAX, 1, &NormalParams::default());
    assert_eq!(out.report.degenerate, 500);
    assert!(out.flags.iter().all(|f| f & FLAG_DEGENERATE != 0));
    assert!(out.normals.iter().all(|n| *n == glam::Vec3::ZERO));
}

#[test]
fn duplicated_points_get_the_same_normal() {
    let scan = generate(&Shape::unit_sphere(), 5_000, 0.0, 1).expect("generate");
    let mut pts = scan.points.clone();
    pts.extend_from_slice(&scan.points);
    let out = normals_of(&pts, 1000, 2, &NormalParams::default());
    assert_eq!(out.report.degenerate, 0);
    for i in 0..scan.points.len() {
        let (a, b) = (out.normals[i], out.normals[i + scan.points.len()]);
        assert!(
            angle_deg(a.as_dvec3(), b.as_dvec3(), false) < 1.0,
            "point {i}"
        );
        assert!(a.as_dvec3().dot(scan.normals[i]) > 0.0);
    }
}

#[test]
fn a_small_island_is_flagged_unoriented() {
    // A big sphere and a far tiny cluster: the cluster is < 1/1000 of points.
    let scan = generate(&Shape::unit_sphere(), 30_000, 0.0, 2).expect("generate");
    let mut pts = scan.points.clone();
    let island =
        generate(&Shape::sphere(DVec3::new(50.0, 0.0, 0.0), 0.01), 20, 0.0, 3).expect("generate");
    pts.extend_from_slice(&island.points);
    let out = normals_of(&pts, u64::MAX, 2, &NormalParams::default());
    let unoriented: Vec<usize> = (0..pts.len())
        .filter(|&i| out.flags[i] & FLAG_UNORIENTED != 0)
        .collect();
    assert_eq!(unoriented, (30_000..30_020).collect::<Vec<_>>());
    assert_eq!(out.report.unoriented, 20);
    // Still signed by its own vote (its highest points face +z), so an
    // open reconstruction can use it: outward, as the big sphere's.
    let top = (30_000..30_020)
        .max_by(|&a, &b| pts[a].z.total_cmp(&pts[b].z))
        .expect("island");
    assert!(out.normals[top].z > 0.0);
    let centre = DVec3::new(50.0, 0.0, 0.0);
    let outward = (30_000..30_020)
        .filter(|&i| out.normals[i].as_dvec3().dot(pts[i] - centre) > 0.0)
        .count();
    assert!(outward >= 18, "{outward} of 20 outward");
}

/// A band, a sphere and seven 20-point islands: the island rule orients
/// five of the islands and cuts through their size class by top id.
/// A Moebius band (which no spanning tree orients consistently, so the
/// tree decides where the sign jumps) stands in for the torus.
fn islands_cloud() -> Vec<DVec3> {
    let mut pts = generate(&Shape::moebius(1.0, 0.4), 36_000, 0.001, 21)
        .expect("generate")
        .points;
    let ball = Shape::sphere(DVec3::new(3.0, 0.5, 0.2), 0.4);
    pts.extend(generate(&ball, 4_000, 0.001, 22).expect("generate").points);
    for k in 0..7 {
        let centre = DVec3::new(4.0 + 0.8 * k as f64, -3.0, 0.5 * k as f64);
        let island = generate(&Shape::sphere(centre, 0.01), 20, 0.0, 30 + k);
        pts.extend(island.expect("generate").points);
    }
    pts
}

#[test]
fn external_orientation_gives_the_in_memory_flips() {
    let pts = islands_cloud();
    let params = NormalParams::default();
    let in_memory = normals_of(&pts, u64::MAX, 2, &params);
    // A promise of 0 bytes keeps no per-point state in memory.
    let tight = RunOptions::new(2).within(MemoryBudget::new(0, 2));
    let external_whole = normals_with(&pts, u64::MAX, tight, &params);
    let external_tiled = normals_with(&pts, 400, tight, &params);
    assert!(
        external_tiled.report.tiles >= 64,
        "{} tiles",
        external_tiled.report.tiles
    );
    assert_eq!(in_memory.report.components, 9);
    assert_eq!(in_memory.report.unoriented, 40);
    for (what, out) in [("untiled", &external_whole), ("tiled", &external_tiled)] {
        assert_eq!(out.report.components, 9, "{what}");
        assert_eq!(out.report.unoriented, 40, "{what}");
        assert!(
            out.bytes == in_memory.bytes,
            "{what}: external flips differ"
        );
    }
}

#[test]
fn external_orientation_on_a_million_points_gives_the_in_memory_flips() {
    // A noisy Moebius band: no consistent orientation exists, so the sign
    // seam shows any difference in the spanning tree.
    let pts = generate(&Shape::moebius(1.0, 0.4), 1_000_000, 0.0005, 23)
        .expect("generate")
        .points;
    let params = NormalParams::default();
    let in_memory = normals_of(&pts, u64::MAX, 2, &params);
    let tight = RunOptions::new(2).within(MemoryBudget::new(0, 2));
    let external = normals_with(&pts, 12_000, tight, &params);
    assert!(
        external.report.tiles >= 64,
        "{} tiles",
        external.report.tiles
    );
    assert!(external.bytes == in_memory.bytes, "external flips differ");
}

/// The library refuses parameters that cannot give normals, before any
/// column is written, whoever calls it (not only the CLI).
#[test]
fn parameters_that_cannot_give_normals_are_refused() {
    use scanmesh::normals::{compute_normals, NormalsError};
    use scanmesh::NoProgress;
    let scan = generate(&Shape::sphere(DVec3::ZERO, 1.0), 2_000, 0.0, 3).unwrap();
    let bad = [
        NormalParams {
            k: 0,
            ..NormalParams::default()
        },
        NormalParams {
            orientation: Orientation::Viewpoint(DVec3::new(0.0, f64::NAN, 0.0)),
            ..NormalParams::default()
        },
        NormalParams {
            orientation: Orientation::SixSources { tau: 1.5 },
            ..NormalParams::default()
        },
        NormalParams {
            orientation: Orientation::SingleSource {
                direction: DVec3::ZERO,
                tau: 0.6,
            },
            ..NormalParams::default()
        },
    ];
    common::with_store(&scan.points, u64::MAX, 1, |store, _| {
        for params in bad {
            let got = compute_normals(store, &params, RunOptions::new(1), &NoProgress);
            assert!(
                matches!(got, Err(NormalsError::BadParameter(_))),
                "{params:?}: {got:?}"
            );
            assert!(!store.has_column(&scanmesh::store::NORMALS));
        }
        assert!(NormalParams::default().validate().is_ok());
    });
}

/// Where stray points sit around a closed surface: far above or below it,
/// inside it, far off to a side, and pairs or trios of those (a pair close
/// together is not isolated: each is the other's nearest neighbour).
fn stray_sets(points: &[DVec3], inside: DVec3, seed: u64) -> Vec<(&'static str, Vec<DVec3>)> {
    let (lo, hi) = points.iter().fold(
        (DVec3::splat(f64::MAX), DVec3::splat(f64::MIN)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    );
    let size = (hi - lo).max_element();
    let mut rng = scanmesh::synth::Rng::new(seed);
    let mut within = |z: f64| DVec3::new(rng.range(lo.x, hi.x), rng.range(lo.y, hi.y), z);
    let above = within(hi.z + rng_height(seed) * size);
    let above_near = above + DVec3::new(0.3, -0.2, 0.1) * 1e-3 * size;
    let below = within(lo.z - 3.0 * size);
    let angle = seed as f64;
    let side = (lo + hi) / 2.0 + DVec3::new(angle.cos(), angle.sin(), 0.1) * 8.0 * size;
    vec![
        ("one far above", vec![above]),
        ("one far below", vec![below]),
        ("one inside", vec![inside]),
        ("one far sideways", vec![side]),
        ("a pair above", vec![above, above_near]),
        ("three anywhere", vec![above, inside, side]),
    ]
}

/// Heights of the stray point above the top, in object sizes, by seed.
fn rng_height(seed: u64) -> f64 {
    [0.5, 2.0, 6.0][seed as usize % 3]
}

/// A closed surface with stray points keeps >= 99 % of its own normals
/// outward, in memory and external, untiled and in 16 or more tiles, on 1
/// and 2 threads (which all agree bit for bit): no one point decides the
/// sign of a component.
fn strays_keep_the_surface_outward(shape: &Shape, inside: DVec3) {
    let n = 20_000;
    for seed in 0..3 {
        let scan = generate(shape, n, 0.0005, 40 + seed).expect("generate");
        for (what, strays) in stray_sets(&scan.points, inside, seed) {
            let mut pts = scan.points.clone();
            pts.extend(&strays);
            let params = NormalParams::default();
            let whole = normals_of(&pts, u64::MAX, 2, &params);
            let outward = (0..n)
                .filter(|&i| whole.normals[i].as_dvec3().dot(scan.normals[i]) > 0.0)
                .count();
            assert!(
                outward * 100 >= n * 99,
                "{} seed {seed}, {what} ({strays:?}): {outward} of {n} outward",
                shape.name()
            );
            let tight = RunOptions::new(2).within(MemoryBudget::new(0, 2));
            let runs = [
                ("in memory, tiled", normals_of(&pts, 400, 2, &params)),
                ("1 thread, tiled", normals_of(&pts, 400, 1, &params)),
                ("external", normals_with(&pts, u64::MAX, tight, &params)),
                ("external, tiled", normals_with(&pts, 400, tight, &params)),
            ];
            for (how, out) in runs {
                // A far stray point stretches the tile grid: 21 to 69 tiles.
                let tiled = how.ends_with("tiled");
                assert!(
                    !tiled || out.report.tiles >= 16,
                    "{how}: {} tiles",
                    out.report.tiles
                );
                assert!(
                    out.bytes == whole.bytes,
                    "{} seed {seed}, {what}: {how} differs from in memory, untiled",
                    shape.name()
                );
            }
        }
    }
}

#[test]
fn stray_points_do_not_turn_a_torus_inside_out() {
    strays_keep_the_surface_outward(&Shape::torus(1.0, 0.3), DVec3::new(1.0, 0.0, 0.0));
}

#[test]
fn stray_points_do_not_turn_a_sphere_inside_out() {
    strays_keep_the_surface_outward(&Shape::unit_sphere(), DVec3::new(0.1, -0.2, 0.05));
}

#[test]
fn stray_points_do_not_turn_a_stepped_block_inside_out() {
    let block = Shape::Steps(scanmesh::synth::StepProfile::stepped_block());
    strays_keep_the_surface_outward(&block, DVec3::new(1.5, 1.5, 1.2));
}
