//! Curvature (paper 5 section 2) through the whole pipeline: sphere and
//! cylinder principal curvatures against the truth, a plane's near-zero
//! curvature, tiled == untiled and 1 thread == 2 threads bit for bit for
//! every neighbourhood kind, and the input-order PLY output.

mod common;

use common::{median, with_store};
use glam::DVec3;
use scanmesh::features::curvature::{CurvatureReport, VALUES};
use scanmesh::features::export::{curvature_output, write_curvature};
use scanmesh::features::{
    compute_curvature, CurvatureParams, HoodChoice, CURVATURE, CURVATURE_FLAGS,
};
use scanmesh::pipeline::{NoProgress, RunOptions};
use scanmesh::store::{PointStore, Rows};
use scanmesh::synth::{generate, Rng, Shape};

/// Curvature values and flags in input order.
struct Out {
    report: CurvatureReport,
    values: Vec<[f32; VALUES]>,
    flags: Vec<u8>,
    ply: Vec<u8>,
}

fn read_back(store: &PointStore) -> (Vec<[f32; VALUES]>, Vec<u8>) {
    let n = store.len() as usize;
    let (mut values, mut flags) = (vec![[0f32; VALUES]; n], vec![0u8; n]);
    let vcol = store.column(&CURVATURE).unwrap();
    let fcol = store.column(&CURVATURE_FLAGS).unwrap();
    let (mut ids, mut v, mut f) = (Vec::new(), Vec::new(), Vec::new());
    for t in store.tiles() {
        store.read_indices(t.start, t.count, &mut ids).unwrap();
        vcol.read_f32(t.start, t.count, &mut v).unwrap();
        fcol.read_u8(t.start, t.count, &mut f).unwrap();
        for (k, &id) in ids.iter().enumerate() {
            values[id as usize].copy_from_slice(&v[VALUES * k..VALUES * (k + 1)]);
            flags[id as usize] = f[k];
        }
    }
    (values, flags)
}

fn run(points: &[DVec3], tile_points: u64, threads: usize, hood: HoodChoice) -> Out {
    with_store(points, tile_points, threads, |store, dir| {
        let params = CurvatureParams {
            hood,
            ..CurvatureParams::default()
        };
        let report = compute_curvature(store, &params, RunOptions::new(threads), &NoProgress)
            .expect("curvature");
        let (values, flags) = read_back(store);
        let path = dir.join("c.ply");
        // A small window: several windows of the input-order writer.
        let spec = curvature_output(&path).expect("a PLY holds the curvature");
        let rows = Rows {
            output: &path,
            window: 1000,
            input: None,
            keep_unselected: false,
            progress: &NoProgress,
        };
        write_curvature(store, &spec, &rows).expect("write");
        Out {
            report,
            values,
            flags,
            ply: std::fs::read(&path).unwrap(),
        }
    })
}

fn radius() -> HoodChoice {
    HoodChoice::default()
}

/// Median relative error of `k1` and `k2` against the truth, over `keep`.
fn check_principal(out: &Out, keep: impl Fn(usize) -> bool, k1: f64, k2: f64, what: &str) {
    let idx: Vec<usize> = (0..out.values.len())
        .filter(|&i| keep(i) && out.flags[i] == 0)
        .collect();
    assert!(
        idx.len() > out.values.len() / 2,
        "{what}: too few points kept"
    );
    let scale = k1.abs().max(k2.abs());
    let e1 = median(
        idx.iter()
            .map(|&i| (out.values[i][0] as f64 - k1).abs())
            .collect(),
    );
    let e2 = median(
        idx.iter()
            .map(|&i| (out.values[i][1] as f64 - k2).abs())
            .collect(),
    );
    assert!(
        e1 <= 0.02 * scale,
        "{what}: k1 median error {e1} (truth {k1})"
    );
    assert!(
        e2 <= 0.02 * scale,
        "{what}: k2 median error {e2} (truth {k2})"
    );
}

#[test]
fn sphere_principal_curvatures_are_one_over_r() {
    let r = 2.0;
    let scan = generate(
        &Shape::sphere(DVec3::new(1.0, -2.0, 0.5), r),
        20_000,
        0.0,
        11,
    )
    .unwrap();
    let out = run(&scan.points, u64::MAX, 2, radius());
    check_principal(&out, |_| true, 1.0 / r, 1.0 / r, "sphere");
    // Gaussian and mean too.
    let k: Vec<f64> = out.values.iter().map(|v| v[3] as f64).collect();
    assert!((median(k) - 0.25).abs() < 0.005, "K");
}

/// A cylinder of radius `r` around the x axis, `len` long, open ends.
fn cylinder(n: usize, r: f64, len: f64, seed: u64) -> Vec<DVec3> {
    let mut rng = Rng::new(seed);
    (0..n)
        .map(|_| {
            let t = rng.range(0.0, std::f64::consts::TAU);
            DVec3::new(rng.range(-len / 2.0, len / 2.0), r * t.cos(), r * t.sin())
        })
        .collect()
}

#[test]
fn cylinder_principal_curvatures_are_one_over_r_and_zero() {
    let (r, len) = (0.5, 4.0);
    let pts = cylinder(20_000, r, len, 3);
    let out = run(&pts, u64::MAX, 2, radius());
    // Away from the open ends, where the neighbourhood is one-sided.
    let inner = |i: usize| pts[i].x.abs() < len / 2.0 - 0.3;
    check_principal(&out, inner, 1.0 / r, 0.0, "cylinder");
    for hood in [
        HoodChoice::Knn { k: 15 },
        HoodChoice::Topological {
            k: 12,
            max_iterations: 10,
        },
    ] {
        let out = run(&pts, u64::MAX, 2, hood);
        check_principal(&out, inner, 1.0 / r, 0.0, &format!("cylinder {hood:?}"));
    }
}

#[test]
fn a_plane_has_no_curvature() {
    let mut rng = Rng::new(5);
    let pts: Vec<DVec3> = (0..10_000)
        .map(|_| {
            let (x, y) = (rng.uniform(), rng.uniform());
            DVec3::new(x, y, 0.3 * x - 0.2 * y + 7.0)
        })
        .collect();
    let out = run(&pts, u64::MAX, 1, radius());
    // sp: expected mean nearest-neighbour distance of 10k uniform points.
    let sp = 0.5 / 100.0;
    let worst = (0..pts.len())
        .filter(|&i| out.flags[i] == 0)
        .map(|i| out.values[i][0].abs().max(out.values[i][1].abs()) as f64)
        .fold(0.0, f64::max);
    assert!(worst < 1e-3 / sp, "largest |k| on a plane: {worst}");
    // Random sampling leaves a corner point or so with fewer than 7 points
    // within r (flagged sparse); nothing else may be flagged.
    let [sparse, degenerate, ill, unoriented] = out.report.meta.flagged;
    assert!(sparse <= 5, "{sparse} sparse");
    assert_eq!([degenerate, ill, unoriented], [0; 3]);
}

#[test]
fn tiled_equals_untiled_and_threads_do_not_matter() {
    let scan = generate(&Shape::torus(1.0, 0.35), 12_000, 0.004, 21).unwrap();
    for hood in [
        radius(),
        HoodChoice::Knn { k: 12 },
        HoodChoice::Topological {
            k: 10,
            max_iterations: 10,
        },
    ] {
        let whole = run(&scan.points, u64::MAX, 1, hood);
        let tiled = run(&scan.points, 150, 2, hood);
        assert!(tiled.report.tiles >= 64, "{} tiles", tiled.report.tiles);
        let bits =
            |o: &Out| -> Vec<u32> { o.values.iter().flatten().map(|v| v.to_bits()).collect() };
        assert_eq!(bits(&whole), bits(&tiled), "{hood:?}: values differ");
        assert_eq!(whole.flags, tiled.flags, "{hood:?}: flags differ");
        assert_eq!(
            whole.report.meta, tiled.report.meta,
            "{hood:?}: stats differ"
        );
        assert!(whole.ply == tiled.ply, "{hood:?}: PLY bytes differ");
    }
}

#[test]
fn ply_output_is_in_input_order() {
    let scan = generate(&Shape::unit_sphere(), 3_000, 0.0, 2).unwrap();
    let out = run(&scan.points, 400, 2, radius());
    let body = out
        .ply
        .windows(11)
        .position(|w| w == b"end_header\n")
        .map(|p| p + 11)
        .unwrap();
    let rec = 24 + 4 * VALUES + 1;
    let recs: Vec<&[u8]> = out.ply[body..].chunks_exact(rec).collect();
    assert_eq!(recs.len(), scan.points.len());
    for (i, r) in recs.iter().enumerate() {
        let x = f64::from_le_bytes(r[0..8].try_into().unwrap());
        assert!((x - scan.points[i].x).abs() < 1e-6, "point {i}: x {x}");
        for v in 0..VALUES {
            let o = 24 + 4 * v;
            let got = f32::from_le_bytes(r[o..o + 4].try_into().unwrap());
            assert_eq!(
                got.to_bits(),
                out.values[i][v].to_bits(),
                "point {i} value {v}"
            );
        }
        assert_eq!(r[rec - 1], out.flags[i]);
    }
}

/// A curvature column is reused only when made from the normals the pass
/// would use: after the normals are recomputed with other parameters (here
/// unoriented), `features` recomputes the curvature, and its lines equal a
/// fresh run's (the stale-normals sequence of issue 13, one stage later).
#[test]
fn curvature_made_from_other_normals_is_recomputed() {
    use scanmesh::features::extract::extract_lines;
    use scanmesh::features::params::FeatureParams;
    use scanmesh::normals::{compute_normals, NormalParams, Orientation};
    use scanmesh::synth::StepProfile;
    let scan = generate(&Shape::Steps(StepProfile::stepped_block()), 8_000, 0.0, 5).unwrap();
    let params = FeatureParams::default();
    let opts = RunOptions::new(1);
    let lines = |store: &mut PointStore| {
        let (graph, report) = extract_lines(store, &params, opts, &NoProgress).unwrap();
        (graph, report.computed_curvature)
    };
    with_store(&scan.points, u64::MAX, 1, |store, _| {
        let (fresh, computed) = lines(store);
        assert!(computed && !fresh.edges.is_empty(), "a block has creases");
        assert_eq!(
            lines(store),
            (fresh.clone(), false),
            "same parameters: reused"
        );
        let unoriented = NormalParams {
            orientation: Orientation::None,
            ..params.curvature.normals
        };
        compute_normals(store, &unoriented, opts, &NoProgress).unwrap();
        assert_eq!(lines(store), (fresh, true), "stale curvature was reused");
    });
}

#[test]
fn curvature_parameters_refuse_a_bad_radius_or_bad_normals() {
    use scanmesh::features::FeaturesError;
    use scanmesh::normals::NormalsError;
    for spacings in [f64::NAN, 0.0, -2.0] {
        let p = CurvatureParams {
            hood: HoodChoice::Radius { spacings },
            ..CurvatureParams::default()
        };
        assert!(
            matches!(p.validate(), Err(FeaturesError::BadParameter(_))),
            "radius {spacings} accepted"
        );
    }
    let mut p = CurvatureParams::default();
    p.normals.k = 0;
    assert!(matches!(
        p.validate(),
        Err(FeaturesError::Normals(NormalsError::BadParameter(_)))
    ));
    assert!(CurvatureParams::default().validate().is_ok());
}
