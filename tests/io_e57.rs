//! E57 input and output: scans made here with the e57 crate's writer (poses
//! with georeferenced translations, cartesian and spherical coordinates,
//! records flagged invalid), read back against a reference computed
//! independently in this file; scan selection; `info` per scan; truncated,
//! corrupt and non-finite files; PLY -> E57 -> PLY.

use e57::{Quaternion, Record, RecordValue, Transform, Translation};
use glam::DVec3;
use scanmesh::io::convert::convert;
use scanmesh::io::e57::list_scans;
use scanmesh::io::inspect::inspect_scans;
use scanmesh::io::{
    create_writer, open_reader, Format, InvalidPolicy, IoError, PointChunk, ReadOptions, WriterSpec,
};
use scanmesh::pipeline::NoProgress;
use scanmesh::synth::Rng;
use std::path::Path;

/// One record as written: its coordinates in the scan's frame, or `None`
/// when written flagged invalid (state 1 or 2).
#[derive(Clone)]
enum Rec {
    Cartesian(DVec3),
    Spherical {
        range: f64,
        azimuth: f64,
        elevation: f64,
    },
    Flagged(i64),
}

struct Scan {
    name: &'static str,
    /// `[w, x, y, z]`, `[x, y, z]`; `None`: no pose element at all.
    pose: Option<([f64; 4], [f64; 3])>,
    spherical: bool,
    recs: Vec<Rec>,
}

/// Rotation of `v` by the unit quaternion `q` (`[w, x, y, z]`), written out
/// as `v + 2w (u x v) + 2 u x (u x v)`, independent of the reader's matrix.
fn rotate(q: [f64; 4], v: DVec3) -> DVec3 {
    let n = q.iter().map(|c| c * c).sum::<f64>().sqrt();
    let (w, u) = (q[0] / n, DVec3::new(q[1], q[2], q[3]) / n);
    let t = 2.0 * u.cross(v);
    v + w * t + u.cross(t)
}

/// The world-frame points of a scan, in record order, flagged ones left out.
fn reference(scan: &Scan) -> Vec<DVec3> {
    scan.recs
        .iter()
        .filter_map(|r| {
            let local = match *r {
                Rec::Cartesian(p) => p,
                Rec::Spherical {
                    range,
                    azimuth,
                    elevation,
                } => {
                    range
                        * DVec3::new(
                            elevation.cos() * azimuth.cos(),
                            elevation.cos() * azimuth.sin(),
                            elevation.sin(),
                        )
                }
                Rec::Flagged(_) => return None,
            };
            Some(match scan.pose {
                Some((q, t)) => rotate(q, local) + DVec3::from_array(t),
                None => local,
            })
        })
        .collect()
}

/// Three posed scans and an empty one: a cartesian scan at a UTM-like
/// translation, an empty scan, a spherical scan with flagged records, and
/// a cartesian scan without a pose whose invalid state flags some records.
fn scans(seed: u64) -> Vec<Scan> {
    scans_of(seed, 1)
}

/// [`scans`] with `1 / div` of the records.
fn scans_of(seed: u64, div: usize) -> Vec<Scan> {
    let mut r = Rng::new(seed);
    let a = (0..700 / div)
        .map(|_| {
            Rec::Cartesian(DVec3::new(
                r.range(-30.0, 30.0),
                r.range(-30.0, 30.0),
                r.range(-2.0, 15.0),
            ))
        })
        .collect();
    let c = (0..900 / div)
        .map(|i| match i % 10 {
            3 => Rec::Flagged(2),
            7 => Rec::Flagged(1),
            _ => Rec::Spherical {
                range: r.range(1.0, 60.0),
                azimuth: r.range(-3.1, 3.1),
                elevation: r.range(-1.5, 1.5),
            },
        })
        .collect();
    let d = (0..400 / div)
        .map(|i| match i % 13 {
            5 => Rec::Flagged(2),
            _ => Rec::Cartesian(DVec3::new(
                r.range(0.0, 5.0),
                r.range(0.0, 5.0),
                r.range(0.0, 5.0),
            )),
        })
        .collect();
    vec![
        Scan {
            name: "station A",
            pose: Some(([0.9, 0.1, -0.3, 0.2], [512_345.678, 4_213_456.789, 123.25])),
            spherical: false,
            recs: a,
        },
        Scan {
            name: "empty",
            pose: None,
            spherical: false,
            recs: Vec::new(),
        },
        Scan {
            name: "station B",
            pose: Some(([0.5, 0.5, 0.5, 0.5], [512_380.5, 4_213_401.25, 120.0])),
            spherical: true,
            recs: c,
        },
        Scan {
            name: "no pose",
            pose: None,
            spherical: false,
            recs: d,
        },
    ]
}

fn write_e57(path: &Path, scans: &[Scan]) {
    let mut w = e57::E57Writer::from_file(path, "{test-file}").unwrap();
    for (i, s) in scans.iter().enumerate() {
        let proto = match s.spherical {
            true => vec![
                Record::SPHERICAL_RANGE_F64,
                Record::SPHERICAL_AZIMUTH_F64,
                Record::SPHERICAL_ELEVATION_F64,
                Record::SPHERICAL_INVALID_STATE,
            ],
            false => vec![
                Record::CARTESIAN_X_F64,
                Record::CARTESIAN_Y_F64,
                Record::CARTESIAN_Z_F64,
                Record::CARTESIAN_INVALID_STATE,
            ],
        };
        let mut pc = w.add_pointcloud(&format!("{{scan-{i}}}"), proto).unwrap();
        pc.set_name(Some(s.name.into()));
        if let Some((q, t)) = s.pose {
            pc.set_transform(Some(Transform {
                rotation: Quaternion {
                    w: q[0],
                    x: q[1],
                    y: q[2],
                    z: q[3],
                },
                translation: Translation {
                    x: t[0],
                    y: t[1],
                    z: t[2],
                },
            }));
        }
        for rec in &s.recs {
            let (a, b, c, state) = match *rec {
                Rec::Cartesian(p) => (p.x, p.y, p.z, 0),
                Rec::Spherical {
                    range,
                    azimuth,
                    elevation,
                } => (range, azimuth, elevation, 0),
                // Flagged records still carry (meaningless) numbers.
                Rec::Flagged(state) => (1.0, 0.5, 0.25, state),
            };
            let v = RecordValue::Double;
            pc.add_point(vec![v(a), v(b), v(c), RecordValue::Integer(state)])
                .unwrap();
        }
        pc.finalize().unwrap();
    }
    w.finalize().unwrap();
}

struct Read {
    xyz: Vec<DVec3>,
    indices: Vec<u64>,
    skipped: u64,
}

fn read(path: &Path, read: impl Into<ReadOptions>, max: usize) -> Result<Read, IoError> {
    let mut r = open_reader(path, read)?;
    assert_eq!(r.info().format, Format::E57);
    let mut out = Read {
        xyz: Vec::new(),
        indices: Vec::new(),
        skipped: 0,
    };
    let mut chunk = PointChunk::default();
    loop {
        let n = r.read_chunk(&mut chunk, max)?;
        assert!(n <= max);
        if n == 0 {
            break;
        }
        assert_eq!(chunk.index_of(0), chunk.first_index);
        out.indices.extend((0..n).map(|i| chunk.index_of(i)));
        out.xyz.extend_from_slice(&chunk.xyz);
    }
    out.skipped = r.skipped();
    Ok(out)
}

/// Largest distance between corresponding points, relative to the extent
/// of `want`.
fn relative_error(got: &[DVec3], want: &[DVec3]) -> f64 {
    assert_eq!(got.len(), want.len());
    let (lo, hi) = want
        .iter()
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(*p), hi.max(*p))
        });
    let extent = (hi - lo).max_element();
    let worst = got
        .iter()
        .zip(want)
        .map(|(a, b)| (*a - *b).abs().max_element())
        .fold(0.0, f64::max);
    worst / extent
}

/// File-wide record numbers of the valid records of the chosen scans.
fn valid_indices(scans: &[Scan], chosen: &[usize]) -> Vec<u64> {
    let mut base = 0u64;
    let mut out = Vec::new();
    for (i, s) in scans.iter().enumerate() {
        if chosen.contains(&i) {
            for (k, r) in s.recs.iter().enumerate() {
                if !matches!(r, Rec::Flagged(_)) {
                    out.push(base + k as u64);
                }
            }
        }
        base += s.recs.len() as u64;
    }
    out
}

fn flagged(scan: &Scan) -> u64 {
    scan.recs
        .iter()
        .filter(|r| matches!(r, Rec::Flagged(_)))
        .count() as u64
}

#[test]
fn every_scan_lands_in_the_world_frame_in_file_order() {
    let seed = 0xE57_0001;
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("site.e57");
    let scans = scans(seed);
    write_e57(&path, &scans);
    let want: Vec<DVec3> = scans.iter().flat_map(reference).collect();
    let all_flagged: u64 = scans.iter().map(flagged).sum();
    for max in [1, 97, 1 << 15] {
        let got = read(&path, InvalidPolicy::Reject, max).unwrap();
        let err = relative_error(&got.xyz, &want);
        assert!(
            err < 1e-6,
            "seed {seed:#x} max {max}: relative error {err:e}"
        );
        assert_eq!(got.indices, valid_indices(&scans, &[0, 1, 2, 3]));
        assert_eq!(got.skipped, all_flagged);
    }
    // Through `convert` (PLY keeps f64): the same points, in the same order.
    let ply = dir.path().join("site.ply");
    let stats = convert(&path, &ply, InvalidPolicy::Reject, &NoProgress).unwrap();
    assert_eq!(stats.points, want.len() as u64);
    assert_eq!(stats.skipped, all_flagged);
    let back = open_reader(&ply, InvalidPolicy::Reject).unwrap();
    let mut xyz = Vec::new();
    read_into(back, &mut xyz);
    let err = relative_error(&xyz, &want);
    assert!(
        err < 1e-6,
        "seed {seed:#x}: converted relative error {err:e}"
    );
}

fn read_into(mut r: Box<dyn scanmesh::io::PointReader>, out: &mut Vec<DVec3>) {
    let mut chunk = PointChunk::default();
    while r.read_chunk(&mut chunk, 1000).unwrap() > 0 {
        out.extend_from_slice(&chunk.xyz);
    }
}

#[test]
fn scans_are_selected_by_index() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("site.e57");
    let scans = scans(0xE57_0002);
    write_e57(&path, &scans);
    let pick = |s: Vec<usize>| ReadOptions {
        policy: InvalidPolicy::Reject,
        scans: Some(s),
        ..ReadOptions::default()
    };
    // Order and repeats in the request do not matter: file order, once.
    let got = read(&path, pick(vec![3, 0, 3]), 50).unwrap();
    let want: Vec<DVec3> = [&scans[0], &scans[3]]
        .into_iter()
        .flat_map(reference)
        .collect();
    assert!(relative_error(&got.xyz, &want) < 1e-6);
    assert_eq!(got.indices, valid_indices(&scans, &[0, 3]));
    assert_eq!(got.skipped, flagged(&scans[3]));
    let only_b = read(&path, pick(vec![2]), 1000).unwrap();
    assert_eq!(only_b.xyz.len(), reference(&scans[2]).len());
    let e = read(&path, pick(vec![4]), 10).err().unwrap().to_string();
    assert!(
        e.contains("site.e57") && e.contains("scan 4") && e.contains("has 4"),
        "{e}"
    );
    // A file without scans refuses a selection.
    let ply = dir.path().join("x.ply");
    convert(&path, &ply, InvalidPolicy::Reject, &NoProgress).unwrap();
    let e = open_reader(&ply, pick(vec![0])).err().unwrap().to_string();
    assert!(e.contains("x.ply") && e.contains("scan selection"), "{e}");
}

/// Runs the binary with `args` then `paths`; its stdout, once it succeeded.
fn scanmesh(args: &[&str], paths: &[&Path]) -> String {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_scanmesh"))
        .args(args)
        .args(paths)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    String::from_utf8(out.stdout).unwrap()
}

#[test]
fn info_lists_every_scan_with_its_counts_and_pose() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("site.e57");
    let scans = scans(0xE57_0003);
    write_e57(&path, &scans);
    let listed = list_scans(&path).unwrap();
    let (whole, per_scan) = inspect_scans(&path, InvalidPolicy::Reject, &NoProgress).unwrap();
    assert_eq!(listed.len(), 4);
    for (i, (s, l)) in scans.iter().zip(&per_scan).enumerate() {
        assert_eq!(l.scan, listed[i]);
        assert_eq!(l.scan.index, i);
        assert_eq!(l.scan.name.as_deref(), Some(s.name));
        assert_eq!(l.scan.records, s.recs.len() as u64);
        assert_eq!(l.points, reference(s).len() as u64, "scan {i}");
        assert_eq!(l.skipped, flagged(s), "scan {i}");
        assert_eq!(l.scan.spherical, s.spherical);
        assert_eq!(l.scan.cartesian, !s.spherical);
        let state = match s.spherical {
            true => "sphericalInvalidState",
            false => "cartesianInvalidState",
        };
        assert_eq!(l.scan.attributes, vec![state]);
        match s.pose {
            Some((q, t)) => {
                let n = q.iter().map(|c| c * c).sum::<f64>().sqrt();
                for (got, want) in l.scan.pose.rotation.iter().zip(q) {
                    assert!((got - want / n).abs() < 1e-15);
                }
                assert_eq!(l.scan.pose.translation, t);
            }
            None => assert!(l.scan.pose.is_identity()),
        }
    }
    let total: usize = scans.iter().map(|s| reference(s).len()).sum();
    assert_eq!(whole.count, total as u64);
    assert_eq!(whole.skipped, scans.iter().map(flagged).sum::<u64>());
    assert_eq!(whole.info.declared_count, Some(2000));
    // The command line prints the same counts.
    let out = scanmesh(&["info", "--json", "-q"], &[&path]);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let listed = v["scans"].as_array().unwrap();
    let points: Vec<u64> = listed
        .iter()
        .map(|s| s["points"].as_u64().unwrap())
        .collect();
    let want: Vec<u64> = scans.iter().map(|s| reference(s).len() as u64).collect();
    assert_eq!(points, want);
    assert_eq!(listed[2]["name"], "station B");
    assert_eq!(listed[2]["invalid"].as_u64(), Some(flagged(&scans[2])));
}

#[test]
fn scans_option_reaches_convert_on_the_command_line() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("site.e57");
    let scans = scans(0xE57_0004);
    write_e57(&path, &scans);
    let out_path = dir.path().join("b.xyz");
    let summary = scanmesh(&["convert", "-q", "--scans", "2,3"], &[&path, &out_path]);
    let skipped = flagged(&scans[2]) + flagged(&scans[3]);
    assert!(
        summary.contains(&format!("({skipped} skipped)")),
        "{summary}"
    );
    let mut xyz = Vec::new();
    read_into(
        open_reader(&out_path, InvalidPolicy::Reject).unwrap(),
        &mut xyz,
    );
    let want: Vec<DVec3> = [&scans[2], &scans[3]]
        .into_iter()
        .flat_map(reference)
        .collect();
    assert!(relative_error(&xyz, &want) < 1e-6);
}

#[test]
fn truncated_and_corrupt_files_are_errors_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("site.e57");
    write_e57(&path, &scans(0xE57_0005));
    let bytes = std::fs::read(&path).unwrap();
    assert_eq!(bytes.len() % 1024, 0);
    let cut = dir.path().join("cut.e57");
    // Cut inside a page, and at a page boundary (the XML at the end is gone).
    for len in [bytes.len() / 2 + 17, bytes.len() / 2 / 1024 * 1024, 40] {
        std::fs::write(&cut, &bytes[..len]).unwrap();
        let e = read(&cut, InvalidPolicy::Skip, 100)
            .err()
            .unwrap()
            .to_string();
        assert!(e.contains("cut.e57") && e.contains("E57"), "{len}: {e}");
        assert!(e.contains("truncated") || e.contains("ends"), "{len}: {e}");
    }
    // A flipped byte in the point data fails its page checksum.
    let mut bad = bytes.clone();
    bad[5000] ^= 0x40;
    let flipped = dir.path().join("flipped.e57");
    std::fs::write(&flipped, &bad).unwrap();
    let e = read(&flipped, InvalidPolicy::Skip, 100)
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("flipped.e57") && e.contains("checksum"), "{e}");
    // Only the magic: no header.
    std::fs::write(&cut, b"ASTM-E57").unwrap();
    let e = read(&cut, InvalidPolicy::Skip, 100)
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("cut.e57"), "{e}");
}

#[test]
fn non_finite_coordinates_and_poses_are_refused_or_skipped() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("nan.e57");
    let mut s = scans(0xE57_0006);
    s[0].recs[10] = Rec::Cartesian(DVec3::new(1.0, f64::NAN, 2.0));
    write_e57(&path, &s);
    let e = read(&path, InvalidPolicy::Reject, 100)
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("nan.e57") && e.contains("record 10"), "{e}");
    let got = read(&path, InvalidPolicy::Skip, 100).unwrap();
    let flagged_all: u64 = s.iter().map(flagged).sum();
    assert_eq!(got.skipped, flagged_all + 1);
    assert!(!got.indices.contains(&10));
    assert!(got.xyz.iter().all(|p| p.is_finite()));

    let pose_path = dir.path().join("pose.e57");
    let mut s = scans(0xE57_0007);
    s[2].pose = Some(([1.0, 0.0, 0.0, 0.0], [f64::INFINITY, 0.0, 0.0]));
    write_e57(&pose_path, &s);
    let e = read(&pose_path, InvalidPolicy::Skip, 100)
        .err()
        .unwrap()
        .to_string();
    assert!(
        e.contains("pose.e57") && e.contains("scan 2") && e.contains("pose"),
        "{e}"
    );
    s[2].pose = Some(([0.0; 4], [0.0; 3]));
    write_e57(&pose_path, &s);
    let e = read(&pose_path, InvalidPolicy::Skip, 100)
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("scan 2") && e.contains("quaternion"), "{e}");
}

#[test]
fn ply_to_e57_to_ply_is_exact() {
    let dir = tempfile::tempdir().unwrap();
    let mut r = Rng::new(0xE57_0008);
    let pts: Vec<DVec3> = (0..5000)
        .map(|_| {
            DVec3::new(
                r.range(5e5, 5.02e5),
                r.range(4.2e6, 4.2e6 + 3e3),
                r.range(-50.0, 400.0),
            )
        })
        .collect();
    let src = dir.path().join("src.ply");
    let mut w = create_writer(&src, &WriterSpec::new(Format::PlyBinaryLe)).unwrap();
    for part in pts.chunks(777) {
        let chunk = PointChunk {
            xyz: part.to_vec(),
            ..PointChunk::default()
        };
        w.write_chunk(&chunk, None).unwrap();
    }
    w.finish().unwrap();
    let e57 = dir.path().join("mid.e57");
    let back = dir.path().join("back.ply");
    assert_eq!(
        convert(&src, &e57, InvalidPolicy::Reject, &NoProgress)
            .unwrap()
            .points,
        5000
    );
    let listed = list_scans(&e57).unwrap();
    assert_eq!(listed.len(), 1);
    assert_eq!(listed[0].records, 5000);
    assert!(listed[0].pose.is_identity());
    assert_eq!(
        convert(&e57, &back, InvalidPolicy::Reject, &NoProgress)
            .unwrap()
            .points,
        5000
    );
    let mut xyz = Vec::new();
    read_into(open_reader(&back, InvalidPolicy::Reject).unwrap(), &mut xyz);
    // f64 all the way: bit for bit.
    assert_eq!(xyz, pts);
}

#[test]
fn an_unfinished_e57_output_leaves_no_file() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("never.e57");
    let mut w = create_writer(&out, &WriterSpec::new(Format::E57)).unwrap();
    let chunk = PointChunk {
        xyz: vec![DVec3::ONE; 10],
        ..PointChunk::default()
    };
    w.write_chunk(&chunk, None).unwrap();
    let bad = PointChunk {
        xyz: vec![DVec3::new(0.0, f64::NAN, 0.0)],
        ..PointChunk::default()
    };
    let e = w.write_chunk(&bad, None).err().unwrap().to_string();
    assert!(e.contains("never.e57") && e.contains("record 10"), "{e}");
    drop(w);
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
}

/// A small file checked in (and, without its page checksums, the E57 fuzz
/// target's seed): `SCANMESH_WRITE_FIXTURES=1` rewrites both.
const FIXTURE: &str = "tests/fixtures/e57/three_scans.e57";
const FUZZ_SEED: &str = "fuzz/seeds/e57/three_scans";
const FIXTURE_SEED: u64 = 0xE57_00F1;

#[test]
fn the_checked_in_fixture_reads_as_its_generator_says() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let path = root.join(FIXTURE);
    let scans = scans_of(FIXTURE_SEED, 10);
    if std::env::var_os("SCANMESH_WRITE_FIXTURES").is_some() {
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        write_e57(&path, &scans);
        let bytes = std::fs::read(&path).unwrap();
        let logical: Vec<u8> = bytes
            .chunks(1024)
            .flat_map(|p| p[..1020].to_vec())
            .collect();
        let seed = root.join(FUZZ_SEED);
        std::fs::create_dir_all(seed.parent().unwrap()).unwrap();
        // The fuzz target's first byte picks policy and scans: 0, all.
        std::fs::write(seed, [&[0u8][..], &logical].concat()).unwrap();
    }
    assert!(std::fs::metadata(&path).unwrap().len() < 100 << 10);
    let want: Vec<DVec3> = scans.iter().flat_map(reference).collect();
    let got = read(&path, InvalidPolicy::Reject, 64).unwrap();
    assert!(relative_error(&got.xyz, &want) < 1e-6);
    assert_eq!(got.skipped, scans.iter().map(flagged).sum::<u64>());
}
