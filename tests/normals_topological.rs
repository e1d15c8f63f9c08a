//! Normals over paper 3's topological neighbourhood (`NormalHood::Topological`):
//! tiled == untiled bit for bit (tangent planes and spanning-tree
//! orientation), 1 thread == 2 threads, better tangent planes than kNN next
//! to a 20:1 density step, radial and outward on a sphere, and the
//! `--neighbours` option of `scanmesh normals` / `scanmesh reconstruct`.

mod common;

use common::{angle_deg, median, normals_of, read_normals, NormalsOut};
use glam::DVec3;
use scanmesh::normals::{NormalHood, NormalParams};
use scanmesh::synth::{generate, Scan, Shape};
use std::process::Command;

const TOPO: NormalHood = NormalHood::Topological { max_iterations: 10 };

fn params(neighbourhood: NormalHood) -> NormalParams {
    NormalParams {
        neighbourhood,
        ..NormalParams::default()
    }
}

fn scan(shape: &Shape, n: usize, noise: f64, seed: u64) -> Scan {
    generate(shape, n, noise, seed).unwrap_or_else(|e| panic!("generate (seed {seed}): {e}"))
}

/// Unsigned angle errors (degrees) of the points `keep` selects, and how
/// many of them agree in sign with the truth.
fn errors(out: &NormalsOut, truth: &Scan, keep: impl Fn(DVec3) -> bool) -> (Vec<f64>, usize) {
    let mut errs = Vec::new();
    let mut agree = 0;
    for (i, n) in out.normals.iter().enumerate() {
        if keep(truth.points[i]) {
            errs.push(angle_deg(n.as_dvec3(), truth.normals[i], true));
            agree += usize::from(n.as_dvec3().dot(truth.normals[i]) > 0.0);
        }
    }
    (errs, agree)
}

#[test]
fn tiled_equals_untiled_bit_for_bit() {
    let seed = 21;
    let s = scan(&Shape::density_step(2.0, 20.0), 40_000, 0.001, seed);
    let p = params(TOPO);
    let whole = normals_of(&s.points, u64::MAX, 2, &p);
    let tiled = normals_of(&s.points, 600, 2, &p);
    assert_eq!(whole.report.tiles, 1);
    assert!(
        tiled.report.tiles >= 64,
        "seed {seed}: only {} tiles",
        tiled.report.tiles
    );
    assert!(tiled.report.forest_edges > 0, "seed {seed}: no forest");
    assert!(
        whole.bytes == tiled.bytes,
        "seed {seed}: tiled output differs from untiled"
    );
}

#[test]
fn one_thread_equals_two_threads() {
    let seed = 3;
    let s = scan(&Shape::unit_sphere(), 20_000, 0.001, seed);
    let p = params(TOPO);
    let one = normals_of(&s.points, 1500, 1, &p);
    let two = normals_of(&s.points, 1500, 2, &p);
    assert!(
        one.bytes == two.bytes,
        "seed {seed}: 1-thread and 2-thread outputs differ"
    );
}

#[test]
fn topological_planes_beat_knn_at_a_density_step() {
    let seed = 5;
    let (n, ratio) = (40_000, 20.0);
    let s = scan(&Shape::density_step(2.0, ratio), n, 0.001, seed);
    // Sparse-side points within a k-th neighbour distance of the step (at
    // x = 0) find their k nearest crowded on the dense side (paper 3's
    // case). Sparse half: n / (ratio + 1) points on area 2.
    let sparse = n as f64 / (ratio + 1.0) / 2.0;
    let k = NormalParams::default().k as f64;
    let band = (k / (std::f64::consts::PI * sparse)).sqrt();
    let near = |p: DVec3| (0.0..band).contains(&p.x);
    let knn = normals_of(&s.points, 4000, 2, &params(NormalHood::Knn));
    let topo = normals_of(&s.points, 4000, 2, &params(TOPO));
    let (knn_errs, knn_agree) = errors(&knn, &s, near);
    let (topo_errs, topo_agree) = errors(&topo, &s, near);
    let count = knn_errs.len();
    assert!(count > 50, "seed {seed}: only {count} points near the step");
    let (knn_med, topo_med) = (median(knn_errs), median(topo_errs));
    eprintln!("sparse side of the step ({count} points): median error kNN {knn_med:.4} deg, topological {topo_med:.4} deg");
    assert!(
        topo_med < knn_med,
        "seed {seed}: topological {topo_med:.4} deg vs kNN {knn_med:.4} deg"
    );
    assert_eq!(
        knn_agree.min(topo_agree),
        count,
        "seed {seed}: flipped near the step"
    );
    for (name, out) in [("kNN", &knn), ("topological", &topo)] {
        let (_, agree) = errors(out, &s, |_| true);
        assert!(
            agree as f64 > 0.99 * n as f64,
            "seed {seed}: {name}: {agree} of {n} agree with the truth's sign"
        );
    }
}

#[test]
fn sphere_normals_are_radial_and_outward() {
    let seed = 7;
    let n = 20_000;
    let s = scan(&Shape::unit_sphere(), n, 0.0, seed);
    let out = normals_of(&s.points, 3000, 2, &params(TOPO));
    assert_eq!(out.report.degenerate, 0, "seed {seed}");
    let (errs, agree) = errors(&out, &s, |_| true);
    let med = median(errs);
    assert!(med < 1.0, "seed {seed}: median angle error {med:.3} deg");
    assert_eq!(agree, n, "seed {seed}: {agree} of {n} point outward");
}

fn scanmesh(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_scanmesh"))
        .args(args)
        .output()
        .expect("run scanmesh")
}

fn write_xyz(points: &[DVec3], path: &std::path::Path) {
    let text: String = points
        .iter()
        .map(|p| format!("{} {} {}\n", p.x, p.y, p.z))
        .collect();
    std::fs::write(path, text).expect("write xyz");
}

#[test]
fn cli_neighbours_topological_matches_the_library() {
    let seed = 9;
    let s = scan(&Shape::unit_sphere(), 5_000, 0.0, seed);
    let dir = tempfile::tempdir().expect("tempdir");
    let input = dir.path().join("sphere.xyz");
    write_xyz(&s.points, &input);
    let output = dir.path().join("n.ply");
    let o = scanmesh(&[
        "normals",
        input.to_str().expect("utf-8 path"),
        "-o",
        output.to_str().expect("utf-8 path"),
        "--neighbours",
        "topological",
        "--tile-points",
        "800",
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (cli, _) = read_normals(&output);
    let lib = normals_of(&s.points, 800, 2, &params(TOPO));
    assert!(cli == lib.normals, "seed {seed}: CLI and library disagree");
    let knn = normals_of(&s.points, 800, 2, &params(NormalHood::Knn));
    assert!(
        knn.normals != lib.normals,
        "seed {seed}: the option made no difference"
    );
    let bad = scanmesh(&[
        "normals",
        input.to_str().expect("utf-8 path"),
        "-o",
        output.to_str().expect("utf-8 path"),
        "--neighbours",
        "radius",
    ]);
    assert!(!bad.status.success());
}

#[test]
fn cli_reconstruct_takes_topological_neighbours() {
    let s = scan(&Shape::unit_sphere(), 5_000, 0.0, 4);
    let dir = tempfile::tempdir().expect("tempdir");
    let input = dir.path().join("sphere.xyz");
    write_xyz(&s.points, &input);
    let mesh = dir.path().join("m.ply");
    let o = scanmesh(&[
        "reconstruct",
        input.to_str().expect("utf-8 path"),
        "-o",
        mesh.to_str().expect("utf-8 path"),
        "--neighbours",
        "topological",
        "--max-iterations",
        "4",
        "--closed",
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8_lossy(&o.stdout);
    let faces: u64 = text
        .split(", ")
        // "N triangles", perhaps followed by what the run changed.
        .find_map(|part| part.split_once(" triangles").map(|(n, _)| n))
        .and_then(|t| t.rsplit(' ').next())
        .and_then(|t| t.parse().ok())
        .unwrap_or_else(|| panic!("no triangle count in {text}"));
    assert!(faces > 1000, "only {faces} triangles: {text}");
}
