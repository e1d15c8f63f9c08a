//! `reconstruct --method projection` through the whole data flow: many
//! tiles against one, and the thread count. The growth runs on a lattice
//! no tiling moves, so many tiles give the very triangles one tile gives
//! (compared by their corners' positions, since vertex indices follow the
//! store order), and one run equals another byte for byte.

mod common;

use glam::DVec3;
use scanmesh::io::read_mesh_any;
use scanmesh::mesh::{quality, self_intersections, Mesh, MeshFormat, QualityReport};
use scanmesh::pipeline::{NoProgress, RunOptions};
use scanmesh::recon::projection::{reconstruct_projection, ProjectionParams, ProjectionReport};
use scanmesh::synth::{generate, mean_spacing_hint, Shape};

fn torus_points(n: usize) -> Vec<DVec3> {
    let shape = Shape::torus(1.0, 0.3);
    let spacing = mean_spacing_hint(&shape, n).expect("spacing");
    generate(&shape, n, 0.1 * spacing, 21).expect("scan").points
}

/// Runs the method on `points` and returns the report, the mesh read back
/// and the file's bytes.
fn run(points: &[DVec3], tile_points: u64, threads: usize) -> (ProjectionReport, Mesh, Vec<u8>) {
    common::with_store(points, tile_points, threads, |store, dir| {
        let out = dir.join("mesh.ply");
        let report = reconstruct_projection(
            store,
            &ProjectionParams::default(),
            &out,
            MeshFormat::PlyBinary,
            RunOptions::new(threads),
            &NoProgress,
        )
        .expect("reconstruct");
        let (v, t) = read_mesh_any(&out).expect("read mesh");
        let bytes = std::fs::read(&out).expect("read bytes");
        (report, Mesh::new(v, t), bytes)
    })
}

fn sound(m: &Mesh) -> QualityReport {
    let q = quality(m);
    assert_eq!(q.non_manifold_edges, 0, "{q:?}");
    assert_eq!(q.inconsistent_edges, 0);
    assert_eq!(q.duplicate_triangles, 0);
    assert_eq!(self_intersections(m).pairs, 0);
    q
}

/// The triangles by their corners' positions, each rotated to start at
/// its smallest corner (the winding kept), sorted.
fn by_position(m: &Mesh) -> Vec<[[u64; 3]; 3]> {
    let key = |v: u32| m.vertices[v as usize].to_array().map(f64::to_bits);
    let mut out: Vec<[[u64; 3]; 3]> = m
        .triangles
        .iter()
        .map(|t| {
            let k = t.map(key);
            let first = (0..3).min_by_key(|&i| k[i]).unwrap_or(0);
            [k[first], k[(first + 1) % 3], k[(first + 2) % 3]]
        })
        .collect();
    out.sort_unstable();
    out
}

#[test]
fn many_tiles_equal_one() {
    let points = torus_points(8_000);
    let (one, m1, _) = run(&points, 1 << 20, 2);
    let (many, mm, _) = run(&points, 80, 2);
    assert_eq!(one.run.tiles, 1);
    assert!(many.run.tiles >= 64, "{} tiles", many.run.tiles);
    // The lattice is cut by planes, edges and corners here.
    assert!(one.jobs >= 20, "{} jobs", one.jobs);
    assert_eq!(one.jobs, many.jobs);
    assert!(many.jobs_run > many.jobs);
    assert!(
        by_position(&m1) == by_position(&mm),
        "the tiles changed the mesh"
    );
    let q = sound(&mm);
    // Every input point is a vertex, in store order; the torus in one
    // piece with a few small holes at most.
    assert_eq!(mm.vertices.len(), points.len());
    assert_eq!(q.components, 1);
    assert!(q.boundary_loops <= 3, "{q:?}");
    let area = 4.0 * std::f64::consts::PI.powi(2) * 0.3;
    assert!(
        (q.total_area - area).abs() < 0.02 * area,
        "area {}",
        q.total_area
    );
    // Outward everywhere: positive volume close to the torus's.
    let volume: f64 = mm
        .triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| mm.vertices[i as usize]);
            a.dot(b.cross(c)) / 6.0
        })
        .sum();
    let expected = 2.0 * std::f64::consts::PI.powi(2) * 0.09;
    assert!(
        (volume - expected).abs() < 0.03 * expected,
        "volume {volume}"
    );
}

#[test]
fn one_thread_equals_two_byte_for_byte() {
    let points = torus_points(6_000);
    let (_, _, a) = run(&points, 100, 1);
    let (_, m, b) = run(&points, 100, 2);
    assert!(a == b, "the output depends on the thread count");
    sound(&m);
}

#[test]
fn command_line_reconstructs_and_evaluates() {
    let dir = tempfile::tempdir().expect("tmp");
    let input = dir.path().join("torus.xyz");
    let text: String = torus_points(3_000)
        .iter()
        .map(|p| format!("{} {} {}\n", p.x, p.y, p.z))
        .collect();
    std::fs::write(&input, text).expect("write input");
    let output = dir.path().join("torus.ply");
    let scanmesh = env!("CARGO_BIN_EXE_scanmesh");
    let status = std::process::Command::new(scanmesh)
        .args([
            "reconstruct",
            "--method",
            "projection",
            "-q",
            "--tile-points",
            "500",
        ])
        .arg(&input)
        .arg("-o")
        .arg(&output)
        .status()
        .expect("run reconstruct");
    assert!(status.success());
    let eval = std::process::Command::new(scanmesh)
        .args(["eval", "--json"])
        .arg(&output)
        .output()
        .expect("run eval");
    assert!(eval.status.success());
    let json: serde_json::Value = serde_json::from_slice(&eval.stdout).expect("json");
    assert_eq!(json["self_intersections"]["pairs"], 0);
    assert_eq!(json["quality"]["non_manifold_edges"], 0);
    assert_eq!(json["quality"]["inconsistent_edges"], 0);
    let share = json["angles"]["sliver_share"].as_f64().expect("share");
    assert!((0.0..0.05).contains(&share), "slivers {share}");
    // A bad parameter is refused before anything is read.
    let bad = std::process::Command::new(scanmesh)
        .args(["reconstruct", "--method", "projection", "--thin", "1.5"])
        .arg(&input)
        .arg("-o")
        .arg(dir.path().join("bad.ply"))
        .output()
        .expect("run");
    assert!(!bad.status.success());
    assert!(String::from_utf8_lossy(&bad.stderr).contains("--thin 1.5"));
}
