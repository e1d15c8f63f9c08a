//! Bad input and bad output paths: every failure is a clean error that names
//! the file (and the record or line where there is one), never a panic, a
//! hang or a huge allocation.

use glam::DVec3;
use scanmesh::geom::Aabb;
use scanmesh::io::{
    create_writer, open_reader, read_mesh, read_mesh_any, read_obj_mesh, Format, InvalidPolicy,
    IoError, LasTransform, PointChunk, PointReader, WriterSpec, DEFAULT_CHUNK,
};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

fn write(d: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let p = d.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

/// Reads to the end; returns the points, or the first error.
fn drain(mut r: Box<dyn PointReader>, max: usize) -> Result<Vec<DVec3>, IoError> {
    let mut chunk = PointChunk::default();
    let mut all = Vec::new();
    while r.read_chunk(&mut chunk, max)? > 0 {
        all.extend_from_slice(&chunk.xyz);
    }
    Ok(all)
}

fn read_err(path: &Path) -> IoError {
    match open_reader(path, InvalidPolicy::Reject) {
        Err(e) => e,
        Ok(r) => drain(r, DEFAULT_CHUNK).expect_err("expected an error"),
    }
}

/// The error's message names the file (its file name at least).
fn assert_names_file(e: &IoError, path: &Path) {
    let name = path.file_name().unwrap().to_string_lossy();
    let msg = e.to_string();
    assert!(msg.contains(&*name), "error does not name {name}: {msg}");
}

fn tmp() -> tempfile::TempDir {
    tempfile::tempdir().unwrap()
}

fn binary_ply(n_declared: u64, records: &[[f64; 3]]) -> Vec<u8> {
    let mut b = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex {n_declared}\n\
         property double x\nproperty double y\nproperty double z\nend_header\n"
    )
    .into_bytes();
    for r in records {
        r.iter().for_each(|v| b.extend_from_slice(&v.to_le_bytes()));
    }
    b
}

fn ascii_ply(n_declared: u64, body: &str) -> Vec<u8> {
    format!(
        "ply\nformat ascii 1.0\nelement vertex {n_declared}\n\
         property float x\nproperty float y\nproperty float z\nend_header\n{body}"
    )
    .into_bytes()
}

fn pts(n: usize) -> Vec<[f64; 3]> {
    (0..n).map(|i| [i as f64, 1.0, 2.0]).collect()
}

#[test]
fn truncated_binary_body() {
    let d = tmp();
    let mut bytes = binary_ply(10, &pts(10));
    bytes.truncate(bytes.len() - 24 * 3 - 5); // 6 whole records and a bit
    let p = write(d.path(), "cut.ply", &bytes);
    for max in [1, 4, 100] {
        let r = open_reader(&p, InvalidPolicy::Reject).unwrap();
        match drain(r, max) {
            Err(
                e @ IoError::Truncated {
                    declared: 10,
                    found: 6,
                    ..
                },
            ) => assert_names_file(&e, &p),
            other => panic!("max {max}: {other:?}"),
        }
    }
}

#[test]
fn truncated_and_short_ascii() {
    let d = tmp();
    // Fewer lines than declared.
    let p = write(d.path(), "short.ply", &ascii_ply(5, "1 2 3\n4 5 6\n"));
    match read_err(&p) {
        e @ IoError::Truncated {
            declared: 5,
            found: 2,
            ..
        } => assert_names_file(&e, &p),
        other => panic!("{other:?}"),
    }
    // Cut in the middle of a line: the last line has no end of line.
    let p = write(d.path(), "cut.ply", &ascii_ply(3, "1 2 3\n4 5 6\n7 8"));
    match read_err(&p) {
        e @ IoError::CutShort {
            record: 2,
            line: 10,
            ..
        } => {
            assert_names_file(&e, &p);
            assert!(e.to_string().contains("line 10"), "{e}");
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn ascii_trailing_garbage() {
    let d = tmp();
    let p = write(d.path(), "extra.ply", &ascii_ply(2, "1 2 3\n4 5 6 7\n"));
    match read_err(&p) {
        e @ IoError::BadRecord { record: 1, .. } => {
            assert!(e.to_string().contains("trailing garbage"), "{e}");
            assert_names_file(&e, &p);
        }
        other => panic!("{other:?}"),
    }
    // More lines than declared when `vertex` is the last element.
    let p = write(d.path(), "more.ply", &ascii_ply(1, "1 2 3\n4 5 6\n\n"));
    match read_err(&p) {
        e @ IoError::TrailingData { declared: 1, .. } => {
            assert!(e.to_string().contains("line 9"), "{e}");
            assert_names_file(&e, &p);
        }
        other => panic!("{other:?}"),
    }
    // A non-number in a record.
    let p = write(d.path(), "word.ply", &ascii_ply(2, "1 2 3\n4 five 6\n"));
    let e = read_err(&p);
    assert!(matches!(e, IoError::BadRecord { record: 1, .. }), "{e:?}");
    assert!(e.to_string().contains("five"), "{e}");
}

#[test]
fn garbage_bytes() {
    let d = tmp();
    let mut junk = Vec::new();
    let mut s = 0x1234_5678u32;
    for _ in 0..5000 {
        s ^= s << 13;
        s ^= s >> 17;
        s ^= s << 5;
        junk.push(s as u8);
    }
    junk[0] = b'Q'; // not a gzip or LAS magic by chance
    for name in ["junk.ply", "junk.xyz", "junk.las", "junk.csv"] {
        let p = write(d.path(), name, &junk);
        let e = read_err(&p);
        assert!(
            matches!(e, IoError::BadHeader { .. } | IoError::BadRecord { .. }),
            "{name}: {e:?}"
        );
        assert_names_file(&e, &p);
    }
    // A PLY header followed by garbage in place of ASCII numbers.
    let mut bytes = ascii_ply(3, "");
    bytes.extend_from_slice(&junk);
    let p = write(d.path(), "body.ply", &bytes);
    let e = read_err(&p);
    assert!(matches!(e, IoError::BadRecord { .. }), "{e:?}");
    assert_names_file(&e, &p);
    // Corrupt gzip.
    let mut gz = vec![0x1f, 0x8b, 8, 0];
    gz.extend_from_slice(&junk[..100]);
    let p = write(d.path(), "bad.ply.gz", &gz);
    let e = read_err(&p);
    assert_names_file(&e, &p);
}

#[test]
fn absurd_header_count_fails_fast() {
    let d = tmp();
    let huge = 1_000_000_000_000_000u64;
    let cases = [
        ("huge_bin.ply", binary_ply(huge, &pts(3))),
        ("huge_ascii.ply", ascii_ply(huge, "1 2 3\n")),
    ];
    for (name, bytes) in cases {
        let p = write(d.path(), name, &bytes);
        let t = Instant::now();
        match read_err(&p) {
            e @ IoError::Truncated { declared, .. } => {
                assert_eq!(declared, huge);
                assert_names_file(&e, &p);
            }
            other => panic!("{name}: {other:?}"),
        }
        assert!(t.elapsed() < Duration::from_secs(2), "{name} slow");
    }
    // An absurd element before the vertices, fixed-size and with lists.
    let h = format!(
        "ply\nformat binary_little_endian 1.0\nelement cam {huge}\nproperty double k\n\
         element vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n"
    );
    let p = write(d.path(), "huge_cam.ply", h.as_bytes());
    let e = read_err(&p);
    assert!(matches!(e, IoError::BadRecord { .. }), "{e:?}");
    assert!(e.to_string().contains("cam"), "{e}");
    // A list claiming 4 billion items.
    let mut b = "ply\nformat binary_little_endian 1.0\nelement vertex 1\n\
                 property list uint uchar junk\nproperty float x\nproperty float y\n\
                 property float z\nend_header\n"
        .as_bytes()
        .to_vec();
    b.extend_from_slice(&u32::MAX.to_le_bytes());
    let p = write(d.path(), "huge_list.ply", &b);
    assert!(matches!(read_err(&p), IoError::Truncated { found: 0, .. }));
}

#[test]
fn bad_headers() {
    let d = tmp();
    let cases: [(&str, &str, &str); 6] = [
        (
            "nox.ply",
            "ply\nformat ascii 1.0\nelement vertex 1\nproperty float y\nproperty float z\nend_header\n1 2\n",
            "'x'",
        ),
        (
            "type.ply",
            "ply\nformat ascii 1.0\nelement vertex 1\nproperty float128 x\nend_header\n",
            "float128",
        ),
        (
            "novertex.ply",
            "ply\nformat ascii 1.0\nelement face 0\nproperty list uchar int v\nend_header\n",
            "vertex",
        ),
        (
            "noend.ply",
            "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n",
            "end_header",
        ),
        (
            "fmt.ply",
            "ply\nformat binary_middle_endian 1.0\nelement vertex 0\nend_header\n",
            "binary_middle_endian",
        ),
        (
            "listx.ply",
            "ply\nformat ascii 1.0\nelement vertex 1\nproperty list uchar float x\n\
             property float y\nproperty float z\nend_header\n1 1 2 3\n",
            "'x'",
        ),
    ];
    for (name, text, needle) in cases {
        let p = write(d.path(), name, text.as_bytes());
        let e = read_err(&p);
        assert!(matches!(e, IoError::BadHeader { .. }), "{name}: {e:?}");
        assert!(e.to_string().contains(needle), "{name}: {e}");
        assert_names_file(&e, &p);
    }
}

#[test]
fn non_finite_reject_names_record() {
    let d = tmp();
    let mut recs = pts(8);
    recs[5][1] = f64::NAN;
    let bin = write(d.path(), "nan.ply", &binary_ply(8, &recs));
    let asc = write(
        d.path(),
        "inf.ply",
        &ascii_ply(4, "1 2 3\n4 5 6\n7 inf 9\n1 1 1\n"),
    );
    let xyz = write(d.path(), "nan.xyz", b"x y z\n1 2 3\n-inf 0 0\n");
    for (p, rec) in [(&bin, 5), (&asc, 2), (&xyz, 1)] {
        match read_err(p) {
            e @ IoError::NonFinite { record, .. } => {
                assert_eq!(record, rec, "{}", p.display());
                assert!(e.to_string().contains(&format!("record {rec}")), "{e}");
                assert_names_file(&e, p);
            }
            other => panic!("{}: {other:?}", p.display()),
        }
    }
}

#[test]
fn non_finite_skip_keeps_input_indices() {
    let d = tmp();
    let n = 50;
    let bad = [0usize, 7, 8, 9, 23, 49];
    let mut recs = pts(n);
    for &b in &bad {
        recs[b][b % 3] = if b % 2 == 0 {
            f64::NAN
        } else {
            f64::NEG_INFINITY
        };
    }
    let mut text = String::new();
    for r in &recs {
        text += &format!("{} {} {}\n", r[0], r[1], r[2]);
    }
    let files = [
        write(d.path(), "skip.ply", &binary_ply(n as u64, &recs)),
        write(d.path(), "skip_a.ply", &ascii_ply(n as u64, &text)),
        write(d.path(), "skip.xyz", text.as_bytes()),
    ];
    let want: Vec<u64> = (0..n as u64)
        .filter(|i| !bad.contains(&(*i as usize)))
        .collect();
    for p in &files {
        for max in [1, 3, 8, 100] {
            let mut r = open_reader(p, InvalidPolicy::Skip).unwrap();
            let mut chunk = PointChunk::default();
            let mut got = Vec::new();
            loop {
                let k = r.read_chunk(&mut chunk, max).unwrap();
                if k == 0 {
                    break;
                }
                assert!(k <= max);
                assert_eq!(chunk.first_index, chunk.index_of(0));
                for i in 0..k {
                    let idx = chunk.index_of(i);
                    assert_eq!(chunk.xyz[i].x, idx as f64, "point keeps its record");
                    got.push(idx);
                }
            }
            assert_eq!(got, want, "{} max {max}", p.display());
            assert_eq!(r.skipped(), bad.len() as u64);
        }
    }
}

#[test]
fn empty_and_unknown_files() {
    let d = tmp();
    for name in ["empty.ply", "empty.xyz", "empty.las", "empty.foo"] {
        let p = write(d.path(), name, b"");
        let e = read_err(&p);
        assert!(matches!(e, IoError::Empty { .. }), "{name}: {e:?}");
        assert_names_file(&e, &p);
    }
    let p = write(d.path(), "points.foo", b"1 2 3\n");
    let e = read_err(&p);
    assert!(matches!(e, IoError::UnknownFormat { .. }), "{e:?}");
    assert_names_file(&e, &p);
    let missing = d.path().join("missing.ply");
    let e = read_err(&missing);
    assert!(matches!(e, IoError::Os { .. }), "{e:?}");
    assert_names_file(&e, &missing);
    // A text file with only a header or comments holds no points.
    let p = write(d.path(), "hdr.csv", b"x,y,z\n# nothing\n\n");
    let r = open_reader(&p, InvalidPolicy::Reject).unwrap();
    assert_eq!(drain(r, 10).unwrap().len(), 0);
}

#[test]
fn xyz_errors_name_line_numbers() {
    let d = tmp();
    let cases: [(&str, &str, &str); 4] = [
        ("a.xyz", "# c\n1 2 3\n4 5 6\n7 x 9\n", "line 4"),
        ("b.xyz", "x y z\n1 2 3 0 0 1\n4 5 6\n", "line 3"),
        ("c.csv", "name,x\nid,value\n1,2,3\n", "line 2"),
        ("d.txt", "1 2 3\n\n\n4 5\n", "line 4"),
    ];
    for (name, text, needle) in cases {
        let p = write(d.path(), name, text.as_bytes());
        let e = read_err(&p);
        assert!(matches!(e, IoError::BadRecord { .. }), "{name}: {e:?}");
        assert!(e.to_string().contains(needle), "{name}: {e}");
        assert_names_file(&e, &p);
    }
}

#[test]
fn bad_meshes() {
    let d = tmp();
    let ply = |faces: &str| {
        format!(
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
             property float z\nelement face 1\nproperty list uchar int vertex_indices\n\
             end_header\n0 0 0\n1 0 0\n0 1 0\n{faces}"
        )
    };
    for (name, faces) in [
        ("range.ply", "3 0 1 3\n"),
        ("neg.ply", "3 0 -1 2\n"),
        ("two.ply", "2 0 1\n"),
        ("none.ply", ""),
    ] {
        let p = write(d.path(), name, ply(faces).as_bytes());
        let e = read_mesh(&p).expect_err(name);
        assert!(matches!(e, IoError::BadRecord { .. }), "{name}: {e:?}");
        assert_names_file(&e, &p);
    }
    for (name, text) in [
        ("range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n"),
        ("zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n"),
        ("rel.obj", "v 0 0 0\nv 1 0 0\nf -1 -2 -3\n"),
        ("word.obj", "v 0 zero 0\n"),
    ] {
        let p = write(d.path(), name, text.as_bytes());
        let e = read_obj_mesh(&p).expect_err(name);
        assert!(e.to_string().contains("line"), "{name}: {e}");
        assert_names_file(&e, &p);
    }
    let p = write(d.path(), "mesh.stl", b"solid x\n");
    assert_names_file(&read_mesh_any(&p).expect_err("stl"), &p);
}

fn point_chunk(n: usize) -> PointChunk {
    PointChunk {
        first_index: 0,
        xyz: (0..n).map(|i| DVec3::new(i as f64, 0.5, -1.0)).collect(),
        normals: None,
        indices: None,
        attrs: Default::default(),
        ..PointChunk::default()
    }
}

fn spec(format: Format) -> WriterSpec {
    WriterSpec {
        format,
        with_normals: false,
        with_flags: false,
        bounds: Some(Aabb::new(
            DVec3::new(0.0, 0.0, -1.0),
            DVec3::new(100.0, 1.0, 0.0),
        )),
        las_transform: None,
        attributes: Default::default(),
        ..WriterSpec::new(format)
    }
}

/// A writer told how many points to expect fails when it gets another
/// number, and leaves nothing under the name asked for (a short output
/// must never look complete).
#[test]
fn a_declared_count_not_written_fails_and_leaves_nothing() {
    let d = tmp();
    for (name, format) in [
        ("a.ply", Format::PlyBinaryLe),
        ("a.pcd", Format::Pcd),
        ("a.las", Format::Las),
        ("a.laz", Format::Laz),
        ("a.xyz", Format::Xyz),
        ("a.e57", Format::E57),
    ] {
        for (declared, written) in [(10, 9), (10, 11), (0, 1)] {
            let path = d.path().join(name);
            let spec = WriterSpec {
                count: Some(declared),
                ..spec(format)
            };
            let mut w = create_writer(&path, &spec).expect("writer");
            w.write_chunk(&point_chunk(written), None).expect("chunk");
            let e = w.finish().expect_err("a count that was not met");
            assert!(
                e.to_string().contains(&format!(
                    "{written} points written where {declared} were declared"
                )),
                "{name}: {e}"
            );
            assert_names_file(&e, &path);
            assert!(!path.exists(), "{name}: a short output was left");
        }
        let path = d.path().join(name);
        let spec = WriterSpec {
            count: Some(7),
            ..spec(format)
        };
        let mut w = create_writer(&path, &spec).expect("writer");
        w.write_chunk(&point_chunk(7), None).expect("chunk");
        assert_eq!(w.finish().expect("the count met"), 7, "{name}");
        std::fs::remove_file(&path).expect("written");
    }
}

const ALL: [(Format, &str); 6] = [
    (Format::PlyBinaryLe, "o.ply"),
    (Format::PlyBinaryBe, "o.ply"),
    (Format::PlyAscii, "o.ply"),
    (Format::Xyz, "o.xyz"),
    (Format::Las, "o.las"),
    (Format::Laz, "o.laz"),
];

#[test]
fn unwritable_output_path() {
    for (format, name) in ALL {
        let p = Path::new("/nonexistent/dir").join(name);
        let e = create_writer(&p, &spec(format)).err().expect("must fail");
        assert!(matches!(e, IoError::Os { .. }), "{format:?}: {e:?}");
        assert!(e.to_string().contains("/nonexistent/dir"), "{e}");
    }
}

#[test]
fn interrupted_writer_leaves_nothing() {
    for (format, name) in ALL {
        let d = tmp();
        let p = d.path().join(name);
        let mut w = create_writer(&p, &spec(format)).unwrap();
        w.write_chunk(&point_chunk(100), None).unwrap();
        drop(w);
        let left: Vec<_> = std::fs::read_dir(d.path()).unwrap().collect();
        assert!(left.is_empty(), "{format:?} left {left:?}");
        // The finished file appears, and only it.
        let mut w = create_writer(&p, &spec(format)).unwrap();
        w.write_chunk(&point_chunk(100), None).unwrap();
        assert!(!p.exists(), "{format:?}: visible before finish");
        assert_eq!(w.finish().unwrap(), 100);
        let left: Vec<_> = std::fs::read_dir(d.path()).unwrap().collect();
        assert_eq!(left.len(), 1, "{format:?}");
        let r = open_reader(&p, InvalidPolicy::Reject).unwrap();
        assert_eq!(drain(r, 33).unwrap().len(), 100);
    }
}

#[test]
fn writer_misuse_is_an_error() {
    let d = tmp();
    // LAS without bounds or transform.
    let mut s = spec(Format::Las);
    s.bounds = None;
    let p = d.path().join("nob.las");
    let e = create_writer(&p, &s).err().expect("no bounds");
    assert!(matches!(e, IoError::Las { .. }), "{e:?}");
    assert_names_file(&e, &p);
    // A point outside the i32 range of the transform: error, not clamp.
    let mut s = spec(Format::Las);
    s.las_transform = Some(LasTransform {
        scale: DVec3::splat(1e-9),
        offset: DVec3::ZERO,
    });
    let p = d.path().join("range.las");
    let mut w = create_writer(&p, &s).unwrap();
    let e = w.write_chunk(&point_chunk(100), None).expect_err("range");
    assert!(e.to_string().contains("point 3"), "{e}");
    assert_names_file(&e, &p);
    drop(w);
    assert!(!p.exists());
    // Normals asked for but missing; NaN coordinates.
    let mut s = spec(Format::PlyBinaryLe);
    s.with_normals = true;
    let p = d.path().join("n.ply");
    let mut w = create_writer(&p, &s).unwrap();
    assert_names_file(&w.write_chunk(&point_chunk(3), None).unwrap_err(), &p);
    let mut c = point_chunk(3);
    c.xyz[2].z = f64::NAN;
    let mut w = create_writer(&p, &spec(Format::Xyz)).unwrap();
    match w.write_chunk(&c, None) {
        Err(e @ IoError::NonFinite { record: 2, .. }) => assert_names_file(&e, &p),
        other => panic!("{other:?}"),
    }
    // gzip output is refused rather than written uncompressed.
    let p = d.path().join("o.xyz.gz");
    assert_names_file(&create_writer(&p, &spec(Format::Xyz)).err().unwrap(), &p);
}

#[test]
fn truncated_las_and_laz() {
    let d = tmp();
    for (format, name) in [(Format::Las, "t.las"), (Format::Laz, "t.laz")] {
        let p = d.path().join(name);
        let mut s = spec(format);
        s.bounds = Some(Aabb::new(
            DVec3::new(0.0, 0.0, -1.0),
            DVec3::new(1e5, 1.0, 0.0),
        ));
        let mut w = create_writer(&p, &s).unwrap();
        w.write_chunk(&point_chunk(100_000), None).unwrap();
        w.finish().unwrap();
        let bytes = std::fs::read(&p).unwrap();
        let cut = write(
            d.path(),
            &format!("cut_{name}"),
            &bytes[..bytes.len() * 2 / 3],
        );
        let e = read_err(&cut);
        assert_names_file(&e, &cut);
        assert!(
            matches!(
                e,
                IoError::Truncated {
                    declared: 100_000,
                    ..
                }
            ),
            "{e:?}"
        );
    }
}

// ---- more data than declared, cut lines, damaged first lines --------------

/// A binary PLY of x, y, z doubles in either byte order; `after` is written
/// after the vertex records (the bodies of later elements, or extra data).
fn binary_ply_order(
    big_endian: bool,
    n_declared: u64,
    records: &[[f64; 3]],
    faces: Option<u64>,
) -> Vec<u8> {
    let order = if big_endian { "big" } else { "little" };
    let mut b = format!(
        "ply\nformat binary_{order}_endian 1.0\nelement vertex {n_declared}\n\
         property double x\nproperty double y\nproperty double z\n"
    );
    if let Some(f) = faces {
        b += &format!("element face {f}\nproperty list uchar int vertex_indices\n");
    }
    b += "end_header\n";
    let mut b = b.into_bytes();
    for r in records {
        for v in r {
            b.extend_from_slice(&if big_endian {
                v.to_be_bytes()
            } else {
                v.to_le_bytes()
            });
        }
    }
    b
}

/// One triangle (0, 1, 2) of the face element above.
fn face(big_endian: bool) -> Vec<u8> {
    let mut b = vec![3u8];
    for i in 0i32..3 {
        b.extend_from_slice(&if big_endian {
            i.to_be_bytes()
        } else {
            i.to_le_bytes()
        });
    }
    b
}

fn read_ok(path: &Path, policy: InvalidPolicy) -> (Vec<DVec3>, u64) {
    let mut r = open_reader(path, policy).unwrap();
    let mut chunk = PointChunk::default();
    let mut all = Vec::new();
    while r.read_chunk(&mut chunk, 3).unwrap() > 0 {
        all.extend_from_slice(&chunk.xyz);
    }
    (all, r.skipped())
}

#[test]
fn binary_ply_with_more_records_than_declared_is_an_error() {
    let d = tmp();
    for big_endian in [false, true] {
        let e = if big_endian { "be" } else { "le" };
        // Ten records, eight declared: the last two were silently dropped.
        let p = write(
            d.path(),
            &format!("more_{e}.ply"),
            &binary_ply_order(big_endian, 8, &pts(10), None),
        );
        for max in [1, 5, 100] {
            let r = open_reader(&p, InvalidPolicy::Reject).unwrap();
            match drain(r, max) {
                Err(
                    e @ IoError::TrailingData {
                        declared: 8,
                        extra_bytes: Some(48),
                        ..
                    },
                ) => {
                    assert_names_file(&e, &p);
                    assert!(e.to_string().contains("2 whole records of 24 bytes"), "{e}");
                }
                other => panic!("{} max {max}: {other:?}", p.display()),
            }
        }
        // Faces legitimately follow the vertices; bytes after them do not.
        let mut bytes = binary_ply_order(big_endian, 10, &pts(10), Some(2));
        bytes.extend(face(big_endian).repeat(2));
        let p = write(d.path(), &format!("faces_{e}.ply"), &bytes);
        assert_eq!(read_ok(&p, InvalidPolicy::Reject).0.len(), 10);
        bytes.extend_from_slice(&7.5f64.to_le_bytes());
        let p = write(d.path(), &format!("faces_more_{e}.ply"), &bytes);
        match read_err(&p) {
            e @ IoError::TrailingData {
                declared: 10,
                extra_bytes: Some(8),
                ..
            } => assert_names_file(&e, &p),
            other => panic!("{other:?}"),
        }
        // Zero bytes after the data are padding, not points.
        let mut bytes = binary_ply_order(big_endian, 10, &pts(10), None);
        bytes.extend([0u8; 100]);
        let p = write(d.path(), &format!("padded_{e}.ply"), &bytes);
        assert_eq!(read_ok(&p, InvalidPolicy::Reject).0, want_pts(10));
    }
}

fn want_pts(n: usize) -> Vec<DVec3> {
    pts(n).iter().map(|p| DVec3::from_array(*p)).collect()
}

fn binary_pcd(n_declared: u64, records: &[[f64; 3]]) -> Vec<u8> {
    let mut b = format!(
        "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\n\
         TYPE F F F\nCOUNT 1 1 1\nWIDTH {n_declared}\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\n\
         POINTS {n_declared}\nDATA binary\n"
    )
    .into_bytes();
    for r in records {
        r.iter()
            .for_each(|v| b.extend_from_slice(&(*v as f32).to_le_bytes()));
    }
    b
}

#[test]
fn binary_pcd_with_more_records_than_declared_is_an_error() {
    let d = tmp();
    let p = write(d.path(), "more.pcd", &binary_pcd(7, &pts(10)));
    for max in [1, 7, 100] {
        let r = open_reader(&p, InvalidPolicy::Reject).unwrap();
        match drain(r, max) {
            Err(
                e @ IoError::TrailingData {
                    declared: 7,
                    extra_bytes: Some(36),
                    ..
                },
            ) => {
                assert_names_file(&e, &p);
                assert!(e.to_string().contains("3 whole records of 12 bytes"), "{e}");
            }
            other => panic!("max {max}: {other:?}"),
        }
    }
    // PCL pads its binary files with zeros: not points, not an error.
    let mut bytes = binary_pcd(10, &pts(10));
    bytes.extend([0u8; 3000]);
    let p = write(d.path(), "padded.pcd", &bytes);
    assert_eq!(read_ok(&p, InvalidPolicy::Reject).0, want_pts(10));
}

/// A LAS file of `n` points by the project's own writer.
fn las_file(d: &Path, name: &str, format: Format, n: usize) -> PathBuf {
    let p = d.join(name);
    let mut s = spec(format);
    s.bounds = Some(Aabb::new(
        DVec3::new(0.0, 0.0, -1.0),
        DVec3::new(n as f64, 1.0, 0.0),
    ));
    let mut w = create_writer(&p, &s).unwrap();
    w.write_chunk(&point_chunk(n), None).unwrap();
    w.finish().unwrap();
    p
}

#[test]
fn las_with_bytes_after_its_points_is_an_error() {
    let d = tmp();
    let p = las_file(d.path(), "ok.las", Format::Las, 100);
    let bytes = std::fs::read(&p).unwrap();
    // The header's point data record length (LAS 1.0-1.4: byte 105).
    let record = u16::from_le_bytes([bytes[105], bytes[106]]) as usize;
    // Two more records, copies of the last: points the header does not count.
    let mut more = bytes.clone();
    more.extend_from_slice(&bytes[bytes.len() - 2 * record..]);
    let more = write(d.path(), "more.las", &more);
    match read_err(&more) {
        e @ IoError::TrailingData {
            declared: 100,
            extra_bytes: Some(_),
            ..
        } => {
            assert_names_file(&e, &more);
            assert!(
                e.to_string()
                    .contains(&format!("2 whole records of {record} bytes")),
                "{e}"
            );
        }
        other => panic!("{other:?}"),
    }
    // Garbage shorter than a record, too.
    let mut junk = bytes.clone();
    junk.extend_from_slice(b"junk");
    let junk = write(d.path(), "junk.las", &junk);
    assert!(matches!(
        read_err(&junk),
        IoError::TrailingData {
            extra_bytes: Some(4),
            ..
        }
    ));
    // Zero padding is not an error.
    let mut padded = bytes.clone();
    padded.extend([0u8; 64]);
    let padded = write(d.path(), "padded.las", &padded);
    assert_eq!(read_ok(&padded, InvalidPolicy::Reject).0.len(), 100);
}

#[test]
fn laz_whose_chunks_hold_more_points_than_declared_is_an_error() {
    let d = tmp();
    let p = las_file(d.path(), "ok.laz", Format::Laz, 120_000);
    // The chunk table follows the points: a whole LAZ is no error.
    assert_eq!(read_ok(&p, InvalidPolicy::Reject).0.len(), 120_000);
    let mut bytes = std::fs::read(&p).unwrap();
    // Declare fewer: the legacy point count (byte 107), and LAS 1.4's
    // 64-bit one (byte 247) when the header is that long.
    bytes[107..111].copy_from_slice(&40_000u32.to_le_bytes());
    let header_size = u16::from_le_bytes([bytes[94], bytes[95]]);
    if header_size >= 375 {
        bytes[247..255].copy_from_slice(&40_000u64.to_le_bytes());
    }
    let fewer = write(d.path(), "fewer.laz", &bytes);
    match read_err(&fewer) {
        e @ IoError::TrailingData {
            declared: 40_000, ..
        } => {
            assert_names_file(&e, &fewer);
            assert!(e.to_string().contains("chunk table"), "{e}");
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn xyz_cut_inside_its_last_number_is_an_error_or_skipped() {
    let d = tmp();
    let text = "1 2 3\n4 5 6\n7 8 9.2";
    let gz = {
        use std::io::Write;
        let mut w = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
        w.write_all(text.as_bytes()).unwrap();
        w.finish().unwrap()
    };
    let files = [
        write(d.path(), "cut.xyz", text.as_bytes()),
        write(
            d.path(),
            "cut_crlf.csv",
            text.replace('\n', "\r\n").as_bytes(),
        ),
        write(d.path(), "cut.xyz.gz", &gz),
        write(d.path(), "one.txt", b"7 8 9.2"),
    ];
    for p in &files {
        match read_err(p) {
            e @ IoError::CutShort { .. } => {
                assert_names_file(&e, p);
                let msg = e.to_string();
                assert!(
                    msg.contains("cut short") && msg.contains("end it with a newline"),
                    "{msg}"
                );
            }
            other => panic!("{}: {other:?}", p.display()),
        }
    }
    match read_err(&files[0]) {
        e @ IoError::CutShort {
            record: 2, line: 3, ..
        } => {
            assert!(e.to_string().contains("line 3"), "{e}")
        }
        other => panic!("{other:?}"),
    }
    // --skip-invalid drops the line and counts it, as a non-finite record.
    let (got, skipped) = read_ok(&files[2], InvalidPolicy::Skip);
    assert_eq!(got, [DVec3::new(1.0, 2.0, 3.0), DVec3::new(4.0, 5.0, 6.0)]);
    assert_eq!(skipped, 1);
    // A whole file: ended by a newline, or by a comment or blank line
    // without one.
    for (name, text) in [
        ("whole.xyz", "1 2 3\n4 5 6\n"),
        ("comment.xyz", "1 2 3\n4 5 6\n# end"),
        ("blank.xyz", "1 2 3\n4 5 6\n  "),
    ] {
        let p = write(d.path(), name, text.as_bytes());
        assert_eq!(read_ok(&p, InvalidPolicy::Reject).0.len(), 2, "{name}");
    }
}

#[test]
fn ascii_ply_and_pcd_cut_inside_their_last_number_are_errors_or_skipped() {
    let d = tmp();
    let pcd = "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2\n\
               HEIGHT 1\nPOINTS 2\nDATA ascii\n1 2 3\n4 5 6.5";
    let files = [
        (
            write(d.path(), "cut.ply", &ascii_ply(2, "1 2 3\n4 5 6.5")),
            9,
        ),
        (write(d.path(), "cut.pcd", pcd.as_bytes()), 11),
    ];
    for (p, line) in &files {
        match read_err(p) {
            e @ IoError::CutShort { record: 1, .. } => {
                assert_names_file(&e, p);
                assert!(e.to_string().contains(&format!("line {line}")), "{e}");
            }
            other => panic!("{}: {other:?}", p.display()),
        }
        let (got, skipped) = read_ok(p, InvalidPolicy::Skip);
        assert_eq!((got, skipped), (vec![DVec3::new(1.0, 2.0, 3.0)], 1));
    }
    // More lines than POINTS in an ASCII PCD.
    let more = pcd.replace("4 5 6.5", "4 5 6\n7 8 9\n");
    let p = write(d.path(), "more.pcd", more.as_bytes());
    match read_err(&p) {
        e @ IoError::TrailingData { declared: 2, .. } => {
            assert_names_file(&e, &p);
            assert!(e.to_string().contains("line 12"), "{e}");
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn xyz_first_line_is_a_header_only_if_it_looks_like_one() {
    let d = tmp();
    // Damaged points are not headers: they were silently dropped.
    for (name, text) in [
        ("corrupt.xyz", "1.0 2.0 x3.0\n4 5 6\n7 8 9\n"),
        ("short.xyz", "1.0 2.0\n4 5 6\n"),
        ("mixed.csv", "x,2.0,z\n4,5,6\n"),
    ] {
        let p = write(d.path(), name, text.as_bytes());
        match read_err(&p) {
            e @ IoError::BadRecord { record: 0, .. } => {
                assert_names_file(&e, &p);
                assert!(e.to_string().contains("line 1"), "{name}: {e}");
            }
            other => panic!("{name}: {other:?}"),
        }
    }
    // Real headers are still skipped: names, quoted names, CloudCompare's
    // `//X`, comments, and the count line of .pts.
    for (name, text) in [
        ("names.xyz", "x y z\n1 2 3\n4 5 6\n"),
        ("upper.csv", "X,Y,Z,R,G,B\n1,2,3,9,9,9\n4,5,6,9,9,9\n"),
        ("quoted.csv", "\"x\",\"y\",\"z\"\n1,2,3\n4,5,6\n"),
        ("cc.txt", "//X Y Z\n1 2 3\n4 5 6\n"),
        ("comment.xyz", "# x y z\n1 2 3\n4 5 6\n"),
        ("count.pts", "2\n1 2 3 7 9 9 9\n4 5 6 7 9 9 9\n"),
        ("units.csv", "x (m),y (m),z (m)\n1,2,3\n4,5,6\n"),
    ] {
        let p = write(d.path(), name, text.as_bytes());
        let (got, _) = read_ok(&p, InvalidPolicy::Reject);
        assert_eq!(
            got,
            [DVec3::new(1.0, 2.0, 3.0), DVec3::new(4.0, 5.0, 6.0)],
            "{name}"
        );
    }
}

/// Rows left out by their flags: only when the flags are written, and a
/// chunk without its flags is an error, not a silent copy.
#[test]
fn rows_are_left_out_by_flags_only_when_flags_are_written() {
    let d = tmp();
    let path = d.path().join("d.ply");
    let no_flags = WriterSpec {
        drop_flagged: 1,
        ..spec(Format::PlyBinaryLe)
    };
    let e = create_writer(&path, &no_flags).err().expect("refused");
    assert!(
        e.to_string().contains("only where the flags are written"),
        "{e}"
    );
    let with_flags = WriterSpec {
        with_flags: true,
        ..no_flags
    };
    let mut w = create_writer(&path, &with_flags).expect("writer");
    let e = w.write_chunk(&point_chunk(4), None).expect_err("no flags");
    assert!(e.to_string().contains("needs 4 flags"), "{e}");
    w.write_chunk(&point_chunk(4), Some(&[0, 1, 2, 3]))
        .expect("flags");
    assert_eq!(
        w.finish().expect("finish"),
        2,
        "rows with flag bit 1 left out"
    );
}
