//! Real PCD files: an organised depth-camera frame (a crop of PCL's test
//! data, NaN where the camera saw nothing) goes through `info` and every
//! processing command without a flag, its NaN pixels left out and
//! counted; PDAL's upper-case field names are read.

use scanmesh::io::{open_reader, InvalidPolicy, PointChunk};
use std::path::{Path, PathBuf};

mod common;
use common::{ok, scanmesh};

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/pcd")
        .join(name)
}

/// The fixture's pixels whose coordinates are NaN, and its pixel count,
/// by this test's own reading of the header and the binary records.
fn nan_pixels(path: &Path) -> (u64, u64) {
    let bytes = std::fs::read(path).expect("read fixture");
    let mut pos = 0;
    let (mut fields, mut sizes, mut points) = (Vec::new(), Vec::new(), 0u64);
    loop {
        let end = pos
            + bytes[pos..]
                .iter()
                .position(|&b| b == b'\n')
                .expect("header");
        let line = std::str::from_utf8(&bytes[pos..end]).expect("text");
        pos = end + 1;
        let words: Vec<&str> = line.split_whitespace().collect();
        match words.first().copied() {
            Some("FIELDS") => fields = words[1..].iter().map(|s| s.to_string()).collect(),
            Some("SIZE") => sizes = words[1..].iter().map(|s| s.parse().unwrap()).collect(),
            Some("POINTS") => points = words[1].parse().unwrap(),
            Some("DATA") => {
                assert_eq!(words[1], "binary");
                break;
            }
            _ => {}
        }
    }
    let record: usize = sizes.iter().sum();
    let offset = |name: &str| -> usize {
        let i = fields.iter().position(|f| f == name).expect("field");
        sizes[..i].iter().sum()
    };
    let at = ["x", "y", "z"].map(offset);
    let mut nan = 0;
    for rec in bytes[pos..].chunks_exact(record).take(points as usize) {
        let v = at.map(|o| f32::from_le_bytes(rec[o..o + 4].try_into().unwrap()));
        if v.iter().any(|c| c.is_nan()) {
            nan += 1;
        }
    }
    (nan, points)
}

fn points_in(path: &Path) -> u64 {
    let mut r = open_reader(path, InvalidPolicy::Reject).expect("open output");
    let mut chunk = PointChunk::default();
    let mut n = 0;
    while r.read_chunk(&mut chunk, 1 << 16).expect("read output") > 0 {
        n += chunk.len() as u64;
    }
    n
}

#[test]
fn an_organised_frame_runs_through_every_command_its_nan_pixels_left_out() {
    let input = fixture("organised_milk.pcd");
    let (nan, pixels) = nan_pixels(&input);
    assert_eq!(pixels, 128 * 96);
    assert!(nan > pixels / 10, "the crop keeps NaN pixels: {nan}");
    let valid = pixels - nan;
    let inp = input.to_str().unwrap();

    let info = ok(scanmesh(&["info", inp, "--json", "-q"]));
    let v: serde_json::Value = serde_json::from_str(&info).expect("json");
    assert_eq!(v["no_return"], nan);
    assert_eq!(v["points"], valid);
    assert_eq!(v["skipped_invalid"], 0);

    let dir = tempfile::tempdir().expect("tmp");
    let out = |name: &str| dir.path().join(name).display().to_string();
    let note = format!("{nan} records of {inp} left out: {nan} without a return");
    let runs: Vec<(Vec<String>, Option<String>)> = vec![
        (
            vec!["normals".into(), inp.into(), "-o".into(), out("n.ply")],
            Some(out("n.ply")),
        ),
        (
            vec!["curvature".into(), inp.into(), "-o".into(), out("k.ply")],
            Some(out("k.ply")),
        ),
        (
            vec!["convert".into(), inp.into(), out("c.ply")],
            Some(out("c.ply")),
        ),
        (
            vec!["tile".into(), inp.into(), "-o".into(), out("s.store")],
            None,
        ),
        (
            vec![
                "neighbors".into(),
                inp.into(),
                "-o".into(),
                out("a.txt"),
                "--format".into(),
                "txt".into(),
                "--neighbours".into(),
                "knn".into(),
            ],
            None,
        ),
        (
            vec!["features".into(), inp.into(), "-o".into(), out("f.ply")],
            None,
        ),
        (
            vec!["reconstruct".into(), inp.into(), "-o".into(), out("m.ply")],
            None,
        ),
        (
            vec![
                "reconstruct".into(),
                inp.into(),
                "-o".into(),
                out("p.ply"),
                "--method".into(),
                "projection".into(),
            ],
            None,
        ),
        (
            vec![
                "reconstruct".into(),
                inp.into(),
                "-o".into(),
                out("d.ply"),
                "--method".into(),
                "delaunay".into(),
            ],
            None,
        ),
    ];
    for (args, per_point) in runs {
        let report = out(&format!("{}.json", args[0]));
        let mut args: Vec<&str> = args.iter().map(String::as_str).collect();
        args.extend(["-q", "--report", &report]);
        let summary = ok(scanmesh(&args));
        assert!(summary.contains(&note), "{args:?}: {summary}");
        let r: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
        assert_eq!(r["left_out"]["no_return"], nan, "{args:?}");
        assert_eq!(r["left_out"]["unselected"], 0, "{args:?}");
        if let Some(p) = per_point {
            assert_eq!(points_in(Path::new(&p)), valid, "{args:?}");
        }
    }
    // The neighbour lists: one line per point kept.
    let lists = std::fs::read_to_string(out("a.txt")).unwrap();
    assert_eq!(
        lists.lines().filter(|l| !l.starts_with('#')).count() as u64,
        valid
    );
}

#[test]
fn nan_in_an_unorganised_cloud_is_still_an_error_unless_skipped() {
    let dir = tempfile::tempdir().expect("tmp");
    let p = dir.path().join("flat.pcd");
    std::fs::write(
        &p,
        "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 3\nHEIGHT 1\nPOINTS 3\nDATA ascii\n0 0 0\nnan nan nan\n1 1 1\n",
    )
    .unwrap();
    let o = scanmesh(&["info", p.to_str().unwrap(), "--json", "-q"]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("flat.pcd") && !err.contains("panicked"),
        "{err}"
    );
    let v: serde_json::Value = serde_json::from_str(&ok(scanmesh(&[
        "info",
        p.to_str().unwrap(),
        "--json",
        "-q",
        "--skip-invalid",
    ])))
    .unwrap();
    assert_eq!(
        (v["points"].as_u64(), v["skipped_invalid"].as_u64()),
        (Some(2), Some(1))
    );
    assert_eq!(v["no_return"], 0);
}

#[test]
fn pdal_upper_case_fields_are_read() {
    let input = fixture("pdal_upper_xyz.pcd");
    let mut r = open_reader(&input, InvalidPolicy::Reject).expect("open");
    assert!(r
        .info()
        .attributes
        .contains(scanmesh::io::Attribute::Intensity));
    let mut chunk = PointChunk::default();
    let mut all = Vec::new();
    let mut intensity = Vec::new();
    while r.read_chunk(&mut chunk, 100).unwrap() > 0 {
        all.extend_from_slice(&chunk.xyz);
        intensity.extend_from_slice(&chunk.attrs.intensity);
    }
    assert_eq!(all.len(), 400);
    // Written by tests/fixtures/pcd/README.md's generator: a grid of
    // 20 x 20 on z = (x^2 + y^2) / 40, intensity = row x 20 + col.
    for (k, p) in all.iter().enumerate() {
        let (row, col) = ((k / 20) as f64, (k % 20) as f64);
        assert_eq!((p.x, p.y), (col * 0.5, row * 0.5), "point {k}");
        assert!(
            (p.z - (p.x * p.x + p.y * p.y) / 40.0).abs() < 1e-12,
            "point {k}"
        );
        assert_eq!(intensity[k], k as u16);
    }
    let dir = tempfile::tempdir().expect("tmp");
    let out = dir.path().join("n.ply");
    let s = ok(scanmesh(&[
        "normals",
        input.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "-q",
    ]));
    assert!(s.starts_with("normals: 400 points"), "{s}");
    assert_eq!(points_in(&out), 400);
}
