//! `--classes` and `--returns`: the points a LAS input's selection keeps
//! are the ones processed, counted against the file read by the `las`
//! crate itself; per-point outputs hold the selected points only
//! (`--unselected drop`, the default) or every point, the unselected
//! flagged (`--unselected keep`); a selection the input cannot answer is
//! an error naming the file.

use glam::DVec3;
use scanmesh::io::{open_reader, InvalidPolicy, PointChunk};
use std::path::{Path, PathBuf};

mod common;
use common::{ok, scanmesh};

fn autzen() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/las/autzen.las")
}

/// Each record's position, class, return number and number of returns,
/// as the `las` crate reads them.
fn records(path: &Path) -> Vec<(DVec3, u8, u8, u8)> {
    let mut r = las::Reader::from_path(path).expect("las reader");
    let d = r.read_all().expect("points");
    let xyz = d
        .x()
        .zip(d.y())
        .zip(d.z())
        .map(|((x, y), z)| DVec3::new(x, y, z));
    xyz.zip(d.classification())
        .zip(d.return_number().zip(d.number_of_returns()))
        .map(|((p, c), (r, n))| (p, c, r, n))
        .collect()
}

/// Positions, normals and flags of a per-point output.
fn read_rows(path: &Path) -> (Vec<DVec3>, Vec<[f32; 3]>) {
    let mut r = open_reader(path, InvalidPolicy::Reject).expect("open output");
    let mut chunk = PointChunk::default();
    let (mut xyz, mut normals) = (Vec::new(), Vec::new());
    while r.read_chunk(&mut chunk, 1 << 16).expect("read") > 0 {
        xyz.extend_from_slice(&chunk.xyz);
        if let Some(n) = &chunk.normals {
            normals.extend(n.iter().map(|v| v.to_array()));
        }
    }
    (xyz, normals)
}

#[test]
fn classes_and_returns_select_what_las_says() {
    let input = autzen();
    let inp = input.to_str().unwrap();
    let recs = records(&input);
    let ground_roofs: Vec<DVec3> = recs
        .iter()
        .filter(|r| r.1 == 2 || r.1 == 6)
        .map(|r| r.0)
        .collect();
    let last = recs.iter().filter(|r| r.2 == r.3).count() as u64;
    let first = recs.iter().filter(|r| r.2 == 1).count() as u64;
    let both = recs.iter().filter(|r| r.2 == 1 && r.1 == 2).count() as u64;
    let n = recs.len() as u64;
    assert!(!ground_roofs.is_empty() && (ground_roofs.len() as u64) < n);
    assert!(last < n && first < n, "the fixture has multiple returns");
    for (flags, want) in [
        (vec!["--classes", "2,6"], ground_roofs.len() as u64),
        (vec!["--returns", "last"], last),
        (vec!["--returns", "first"], first),
        (vec!["--returns", "first", "--classes", "2"], both),
    ] {
        let mut args = vec!["info", inp, "--json", "-q"];
        args.extend(&flags);
        let v: serde_json::Value = serde_json::from_str(&ok(scanmesh(&args))).unwrap();
        assert_eq!(v["points"], want, "{flags:?}");
        assert_eq!(v["unselected"], n - want, "{flags:?}");
    }

    // Drop (default): the output holds the selected points, in input
    // order, with the input's own coordinates.
    let dir = tempfile::tempdir().expect("tmp");
    let out = dir.path().join("n.ply");
    let report = dir.path().join("r.json");
    let s = ok(scanmesh(&[
        "normals",
        inp,
        "-o",
        out.to_str().unwrap(),
        "--classes",
        "2,6",
        "-q",
        "--report",
        report.to_str().unwrap(),
    ]));
    let left = n - ground_roofs.len() as u64;
    assert!(
        s.contains(&format!(
            "{left} records of {inp} left out: {left} not selected; not in the output"
        )),
        "{s}"
    );
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    assert_eq!(r["left_out"]["unselected"], left);
    let (xyz, normals) = read_rows(&out);
    assert_eq!(xyz, ground_roofs);
    assert!(normals.iter().all(|n| n.iter().all(|c| c.is_finite())));

    // Keep: every input point, in input order; the unselected with a NaN
    // normal, the selected with the normals of the dropped run.
    let kept = dir.path().join("k.ply");
    ok(scanmesh(&[
        "normals",
        inp,
        "-o",
        kept.to_str().unwrap(),
        "--classes",
        "2,6",
        "--unselected",
        "keep",
        "-q",
    ]));
    let (kxyz, knormals) = read_rows(&kept);
    let all: Vec<DVec3> = recs.iter().map(|r| r.0).collect();
    assert_eq!(kxyz, all);
    let mut selected = normals.iter();
    for (rec, nrm) in recs.iter().zip(&knormals) {
        match rec.1 == 2 || rec.1 == 6 {
            true => assert_eq!(Some(nrm), selected.next()),
            false => assert!(nrm.iter().all(|c| c.is_nan()), "{rec:?}: {nrm:?}"),
        }
    }

    // convert: the same rows, LAS to LAS.
    let c = dir.path().join("c.las");
    ok(scanmesh(&[
        "convert",
        inp,
        c.to_str().unwrap(),
        "--returns",
        "last",
        "-q",
    ]));
    let back: Vec<DVec3> = records(&c).iter().map(|r| r.0).collect();
    let want: Vec<DVec3> = recs.iter().filter(|r| r.2 == r.3).map(|r| r.0).collect();
    assert_eq!(back, want);
}

#[test]
fn a_selection_the_input_cannot_answer_is_an_error_naming_it() {
    let dir = tempfile::tempdir().expect("tmp");
    let xyz = dir.path().join("plain.xyz");
    std::fs::write(&xyz, "0 0 0\n1 0 0\n0 1 0\n1 1 0\n").unwrap();
    let out = dir.path().join("n.ply");
    for args in [
        vec![
            "normals",
            xyz.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--classes",
            "2",
        ],
        vec!["info", xyz.to_str().unwrap(), "--returns", "first"],
        vec![
            "reconstruct",
            xyz.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--classes",
            "2",
        ],
    ] {
        let o = scanmesh(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{args:?}");
        assert!(
            err.contains("plain.xyz") && !err.contains("panicked"),
            "{err}"
        );
    }
    // Last returns need a number of returns: LAS only.
    let pcd = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/pcd/pdal_upper_xyz.pcd");
    let o = scanmesh(&["info", pcd.to_str().unwrap(), "--returns", "last"]);
    assert!(String::from_utf8_lossy(&o.stderr).contains("only LAS/LAZ"));
    // A mesh has no row per point to keep.
    let o = scanmesh(&[
        "reconstruct",
        autzen().to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--classes",
        "2",
        "--unselected",
        "keep",
    ]);
    assert!(String::from_utf8_lossy(&o.stderr).contains("--unselected keep"));
    assert!(!out.exists());
}

/// Nearest distance from `p` to any of `set`, over the axes `dims`.
fn nearest(p: DVec3, set: &[DVec3], dims: usize) -> f64 {
    set.iter()
        .map(|q| {
            let d = (*q - p).to_array();
            d[..dims].iter().map(|c| c * c).sum::<f64>()
        })
        .fold(f64::INFINITY, f64::min)
        .sqrt()
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

#[test]
fn a_mesh_of_ground_only_stays_on_the_ground() {
    // 5,535 points of PDAL's autzen_trim.las (a 160 m square with houses):
    // 1,860 ground (class 2), the rest unclassified (roofs, trees).
    let input =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/las/autzen_town_cut.las");
    let inp = input.to_str().unwrap();
    let recs = records(&input);
    let ground: Vec<DVec3> = recs.iter().filter(|r| r.1 == 2).map(|r| r.0).collect();
    let other: Vec<DVec3> = recs.iter().filter(|r| r.1 != 2).map(|r| r.0).collect();
    assert_eq!((ground.len(), recs.len()), (1860, 5535));
    let sp = ground
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let rest: Vec<DVec3> = [&ground[..i], &ground[i + 1..]].concat();
            nearest(*p, &rest, 3)
        })
        .sum::<f64>()
        / ground.len() as f64;
    // Unclassified points with no ground point within 3 sp horizontally:
    // roofs and canopies over ground the scanner did not see.
    let above: Vec<DVec3> = other
        .iter()
        .copied()
        .filter(|p| nearest(*p, &ground, 2) > 3.0 * sp)
        .collect();
    assert!(
        above.len() > 20,
        "{} points over unseen ground",
        above.len()
    );

    let dir = tempfile::tempdir().expect("tmp");
    let mesh_of = |name: &str, flags: &[&str]| {
        let out = dir.path().join(name);
        let mut args = vec!["reconstruct", inp, "-o", out.to_str().unwrap(), "-q"];
        args.extend(flags);
        ok(scanmesh(&args));
        scanmesh::io::read_mesh_any(&out).expect("mesh").0
    };
    let selected = mesh_of("ground.ply", &["--classes", "2"]);
    let whole = mesh_of("all.ply", &[]);
    let far = |mesh: &[DVec3]| {
        mesh.iter()
            .map(|v| nearest(*v, &ground, 3) / sp)
            .fold(0.0, f64::max)
    };
    // Measured: 4.12 sp with --classes 2 (the mesh bridges ground the
    // roofs hid, at ground height), 17.9 sp without (the roofs).
    assert!(far(&selected) < 5.0, "{}", far(&selected));
    assert!(far(&whole) > 10.0, "{}", far(&whole));
    let from_above =
        |mesh: &[DVec3]| median(above.iter().map(|p| nearest(*p, mesh, 3) / sp).collect());
    // Measured: 7.95 sp and 0.72 sp.
    assert!(from_above(&selected) > 5.0, "{}", from_above(&selected));
    assert!(from_above(&whole) < 1.5, "{}", from_above(&whole));

    // Per-point outputs of the same selection hold the ground's rows.
    let k = dir.path().join("k.ply");
    ok(scanmesh(&[
        "curvature",
        inp,
        "-o",
        k.to_str().unwrap(),
        "--classes",
        "2",
        "-q",
    ]));
    assert_eq!(read_rows(&k).0, ground);
}

#[test]
fn curvature_keeps_the_unselected_rows_when_asked() {
    let input = autzen();
    let inp = input.to_str().unwrap();
    let recs = records(&input);
    let dir = tempfile::tempdir().expect("tmp");
    let (d, k) = (dir.path().join("d.ply"), dir.path().join("k.ply"));
    for (out, mode) in [(&d, "drop"), (&k, "keep")] {
        let args = [
            "curvature",
            inp,
            "-o",
            out.to_str().unwrap(),
            "--returns",
            "first",
        ];
        ok(scanmesh(
            &[&args[..], &["--unselected", mode, "-q"]].concat(),
        ));
    }
    let first: Vec<DVec3> = recs.iter().filter(|r| r.2 == 1).map(|r| r.0).collect();
    assert_eq!(read_rows(&d).0, first);
    assert_eq!(
        read_rows(&k).0,
        recs.iter().map(|r| r.0).collect::<Vec<_>>()
    );
    // The records: x y z (f64), k1 k2 H K residual (f32), flags (u8).
    let body = |p: &Path| {
        let b = std::fs::read(p).unwrap();
        let h = b.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
        b[h..]
            .chunks_exact(45)
            .map(|r| r.to_vec())
            .collect::<Vec<_>>()
    };
    let (dropped, kept) = (body(&d), body(&k));
    let mut selected = dropped.iter();
    for (rec, row) in recs.iter().zip(&kept) {
        match rec.2 == 1 {
            true => assert_eq!(Some(row), selected.next()),
            false => {
                assert_eq!(row[44], 128, "{rec:?}");
                let k1 = f32::from_le_bytes(row[24..28].try_into().unwrap());
                assert!(k1.is_nan());
            }
        }
    }
    assert!(selected.next().is_none());
}

/// Each LAS record's first `len` bytes (every field of the input's
/// records, the extra bytes scanmesh appends left aside), as the `las`
/// crate reads them.
fn raw_records(path: &Path, len: usize) -> Vec<Vec<u8>> {
    let mut r = las::Reader::from_path(path).expect("las reader");
    let own = usize::from(r.header().point_format().len());
    let d = r.read_all().expect("points");
    d.raw_bytes()
        .chunks(own)
        .map(|c| c[..len].to_vec())
        .collect()
}

/// A LAS output of a selection is the selected records as they came (or,
/// with `keep`, every record): a selection must carry each point's own
/// record with it, not the record of the point before.
#[test]
fn a_selection_written_to_las_keeps_each_points_own_record() {
    let input =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/las/autzen_town_cut.las");
    let dir = tempfile::tempdir().expect("tempdir");
    let len = usize::from(
        las::Reader::from_path(&input)
            .expect("las reader")
            .header()
            .point_format()
            .len(),
    );
    let all = raw_records(&input, len);
    let classes = records(&input);
    let ground: Vec<Vec<u8>> = all
        .iter()
        .zip(&classes)
        .filter(|(_, c)| c.1 == 2)
        .map(|(r, _)| r.clone())
        .collect();
    assert!(ground.len() > 100 && ground.len() < all.len());
    let input = input.to_str().expect("utf-8");
    for (cmd, name, keep) in [
        ("convert", "c.las", false),
        ("convert", "ck.laz", true),
        ("normals", "n.laz", false),
        ("normals", "nk.las", true),
    ] {
        let out = dir.path().join(name);
        let out = out.to_str().expect("utf-8");
        let mut args = match cmd {
            "convert" => vec!["convert", input, out],
            _ => vec!["normals", input, "-o", out],
        };
        args.extend(["--classes", "2"]);
        if keep {
            args.extend(["--unselected", "keep"]);
        }
        ok(scanmesh(&args));
        let want = if keep { &all } else { &ground };
        assert!(&raw_records(Path::new(out), len) == want, "{cmd} -> {name}");
    }
}
