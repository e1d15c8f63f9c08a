//! Every reconstruction checks what it promised of its mesh, and says so:
//! the summary line's `checked:` part and the report's `mesh_audit`, from
//! the command line. A closed scan keeps the `--closed` promise; an open
//! sheet cannot, so its mesh is written as `NAME.incomplete.ply` and the
//! run fails naming the boundary it found.

use glam::DVec3;
use scanmesh::io::read_mesh_any;
use scanmesh::mesh::{quality, Mesh};
use scanmesh::synth::{generate, Shape};
use std::path::Path;

mod common;
use common::scanmesh;

fn write_xyz(path: &Path, points: &[DVec3]) {
    let text: String = points
        .iter()
        .map(|p| format!("{} {} {}\n", p.x, p.y, p.z))
        .collect();
    std::fs::write(path, text).expect("write input");
}

fn report(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).expect("report")).expect("json")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

#[test]
fn a_closed_torus_keeps_the_closed_promise_and_says_so() {
    let dir = tempfile::tempdir().expect("tmp");
    let input = dir.path().join("torus.xyz");
    let scan = generate(&Shape::torus(1.0, 0.3), 20_000, 0.0, 3).expect("generate");
    write_xyz(&input, &scan.points);
    let out = dir.path().join("torus.ply");
    let json = dir.path().join("run.json");
    let (i, o, r) = (input.to_str(), out.to_str(), json.to_str());
    let run = scanmesh(&[
        "reconstruct",
        "--closed",
        "-q",
        "--tile-points",
        "5000",
        i.unwrap_or(""),
        "-o",
        o.unwrap_or(""),
        "--report",
        r.unwrap_or(""),
    ]);
    assert!(run.status.success(), "{}", text(&run.stderr));
    let line = text(&run.stdout);
    assert!(
        line.contains(
            "checked: 1 piece, closed, 0 non-manifold edges, 0 non-manifold vertices, 0 inconsistently wound, volume +"
        ),
        "{line}"
    );
    let audit = &report(&json)["mesh_audit"];
    assert_eq!(audit["boundary_edges"], 0);
    assert_eq!(audit["closed_components"], 1);
    assert_eq!(audit["euler_characteristic"], 0);
    let truth = 2.0 * std::f64::consts::PI.powi(2) * 0.3 * 0.3;
    let volume = audit["volume"].as_f64().expect("volume");
    assert!(
        (volume - truth).abs() < 0.03 * truth,
        "{volume} against {truth}"
    );
    // What the file holds, counted again in memory.
    let (v, t) = read_mesh_any(&out).expect("read");
    let q = quality(&Mesh::new(v, t));
    assert!(q.watertight && q.consistently_oriented, "{q}");
    assert_eq!(audit["edges"], q.edges);
}

#[test]
fn an_open_sheet_comes_out_closed_when_closed_is_asked() {
    let dir = tempfile::tempdir().expect("tmp");
    let input = dir.path().join("sheet.xyz");
    let scan = generate(&Shape::hole_plane(2.0, 0.4), 30_000, 0.0, 5).expect("generate");
    write_xyz(&input, &scan.points);
    let out = dir.path().join("sheet.ply");
    let json = dir.path().join("run.json");
    let (i, o, r) = (input.to_str(), out.to_str(), json.to_str());
    let args = ["reconstruct", "-q", i.unwrap_or(""), "-o", o.unwrap_or("")];
    // Open, nothing is promised: the counts are printed.
    let open = scanmesh(&args);
    assert!(open.status.success(), "{}", text(&open.stderr));
    let line = text(&open.stdout);
    assert!(
        line.contains("checked: 1 piece, 2 boundary loops ("),
        "{line}"
    );
    std::fs::remove_file(&out).expect("remove");
    // Closed: every corner has a sign, so the sheet comes out as a closed
    // slab (the winding number is below 1/2 on both sides of an open
    // sheet, so the band's inner side closes it), its hole a tunnel.
    let closed = scanmesh(&[&args[..], &["--closed", "--report", r.unwrap_or("")]].concat());
    assert!(closed.status.success(), "{}", text(&closed.stderr));
    let line = text(&closed.stdout);
    assert!(line.contains("checked: 1 piece, closed, "), "{line}");
    let (v, t) = read_mesh_any(&out).expect("read");
    let q = quality(&Mesh::new(v, t));
    assert!(q.watertight && q.consistently_oriented, "{q}");
    assert_eq!(q.non_manifold_edges, 0, "{q}");
    assert_eq!(q.euler_characteristic, 0, "a slab with one tunnel: {q}");
    let audit = &report(&json)["mesh_audit"];
    assert_eq!(audit["edges"], q.edges);
    assert!(audit["volume"].as_f64().expect("volume") > 0.0);
}

#[test]
fn projection_and_delaunay_print_their_checks() {
    let dir = tempfile::tempdir().expect("tmp");
    let input = dir.path().join("torus.xyz");
    let scan = generate(&Shape::torus(1.0, 0.3), 4_000, 0.0, 7).expect("generate");
    write_xyz(&input, &scan.points);
    for method in ["projection", "delaunay"] {
        let out = dir.path().join(format!("{method}.ply"));
        let (i, o) = (input.to_str().unwrap_or(""), out.to_str().unwrap_or(""));
        let run = scanmesh(&["reconstruct", "--method", method, "-q", i, "-o", o]);
        assert!(run.status.success(), "{method}: {}", text(&run.stderr));
        let line = text(&run.stdout);
        let (v, t) = read_mesh_any(&out).expect("read");
        let q = quality(&Mesh::new(v, t));
        // The counts printed are the file's.
        let plural = |n: u64, one: &str, many: &str| match n {
            1 => format!("1 {one}"),
            n => format!("{n} {many}"),
        };
        let want = format!(
            "{}, {}, {} inconsistently wound",
            plural(
                q.non_manifold_edges,
                "non-manifold edge",
                "non-manifold edges"
            ),
            plural(
                q.non_manifold_vertices,
                "non-manifold vertex",
                "non-manifold vertices"
            ),
            q.inconsistent_edges
        );
        assert!(line.contains("; checked: "), "{method}: {line}");
        assert!(line.contains(&want), "{method}: {want} not in {line}");
        if method == "projection" {
            // What it promises by construction.
            assert_eq!((q.non_manifold_edges, q.inconsistent_edges), (0, 0));
        }
    }
}
