//! PLY files of odd layouts in all three encodings (every scalar type, lists
//! in the vertex, elements before and after it), meshes (PLY, OBJ, gzip) and
//! the checked-in fixtures.

mod common;

use common::read_all;
use flate2::write::GzEncoder;
use flate2::Compression;
use glam::{DVec3, Vec3};
use scanmesh::io::{
    open_reader, read_mesh, read_mesh_any, read_obj_mesh, Format, InvalidPolicy, DEFAULT_CHUNK,
};
use scanmesh::synth::Rng;
use std::io::Write;
use std::path::{Path, PathBuf};

fn tmp() -> tempfile::TempDir {
    tempfile::tempdir().unwrap()
}

fn gzip_file(src: &Path, dst: &Path, members: usize) {
    let data = std::fs::read(src).unwrap();
    let mut out = Vec::new();
    let step = data.len().div_ceil(members);
    for part in data.chunks(step) {
        let mut gz = GzEncoder::new(Vec::new(), Compression::fast());
        gz.write_all(part).unwrap();
        out.extend(gz.finish().unwrap());
    }
    std::fs::write(dst, out).unwrap();
}

// ---- hand-built PLY files of odd layouts -------------------------------

#[derive(Clone, Copy, PartialEq)]
enum Enc {
    Ascii,
    Le,
    Be,
}

enum Kind {
    Scalar(&'static str),
    List(&'static str, &'static str),
}

enum Val {
    S(f64),
    L(Vec<f64>),
}

struct El {
    name: &'static str,
    props: Vec<(&'static str, Kind)>,
    rows: Vec<Vec<Val>>,
    /// Declared count, if it differs from the rows present.
    declared: Option<usize>,
}

fn encode_scalar(out: &mut Vec<u8>, enc: Enc, ty: &str, v: f64) {
    let mut b: Vec<u8> = match ty {
        "char" | "int8" => vec![v as i8 as u8],
        "uchar" | "uint8" => vec![v as u8],
        "short" | "int16" => (v as i16).to_le_bytes().to_vec(),
        "ushort" | "uint16" => (v as u16).to_le_bytes().to_vec(),
        "int" | "int32" => (v as i32).to_le_bytes().to_vec(),
        "uint" | "uint32" => (v as u32).to_le_bytes().to_vec(),
        "float" | "float32" => (v as f32).to_le_bytes().to_vec(),
        "double" | "float64" => v.to_le_bytes().to_vec(),
        other => panic!("type {other}"),
    };
    match enc {
        Enc::Ascii => {
            let s = match ty {
                "float" | "float32" => format!("{} ", v as f32),
                "double" | "float64" => format!("{v} "),
                _ => format!("{} ", v as i64),
            };
            out.extend_from_slice(s.as_bytes());
        }
        Enc::Le => out.extend_from_slice(&b),
        Enc::Be => {
            b.reverse();
            out.extend_from_slice(&b);
        }
    }
}

fn build_ply(enc: Enc, els: &[El]) -> Vec<u8> {
    let format = match enc {
        Enc::Ascii => "ascii",
        Enc::Le => "binary_little_endian",
        Enc::Be => "binary_big_endian",
    };
    let mut h = format!("ply\nformat {format} 1.0\ncomment odd layout\nobj_info test\n");
    for el in els {
        let n = el.declared.unwrap_or(el.rows.len());
        h += &format!("element {} {n}\n", el.name);
        for (name, kind) in &el.props {
            h += &match kind {
                Kind::Scalar(t) => format!("property {t} {name}\n"),
                Kind::List(c, t) => format!("property list {c} {t} {name}\n"),
            };
        }
        h += "comment between elements\n";
    }
    h += "end_header\n";
    let mut out = h.into_bytes();
    for el in els {
        for row in &el.rows {
            for ((_, kind), v) in el.props.iter().zip(row) {
                match (kind, v) {
                    (Kind::Scalar(t), Val::S(x)) => encode_scalar(&mut out, enc, t, *x),
                    (Kind::List(c, t), Val::L(xs)) => {
                        encode_scalar(&mut out, enc, c, xs.len() as f64);
                        xs.iter().for_each(|&x| encode_scalar(&mut out, enc, t, x));
                    }
                    _ => panic!("row does not match layout"),
                }
            }
            if enc == Enc::Ascii {
                out.push(b'\n');
            }
        }
    }
    out
}

/// A `camera` element (scalars and a list) to be skipped before the vertices.
fn camera(r: &mut Rng) -> El {
    El {
        name: "camera",
        props: vec![
            ("view", Kind::Scalar("float")),
            ("ids", Kind::List("uchar", "int")),
            ("k", Kind::Scalar("ushort")),
        ],
        rows: (0..3)
            .map(|i| {
                let ids = (0..i * 2).map(|_| (r.next_u64() % 1000) as f64).collect();
                vec![Val::S(r.range(-1.0, 1.0)), Val::L(ids), Val::S(i as f64)]
            })
            .collect(),
        declared: None,
    }
}

/// Faces after the vertices, which a point reader skips: it reads them only
/// to find where the file must end. `declared`: a count that may differ
/// from the rows written.
fn faces_after(r: &mut Rng, declared: Option<usize>) -> El {
    El {
        name: "face",
        props: vec![("vertex_indices", Kind::List("uchar", "int"))],
        rows: (0..5)
            .map(|i| {
                let corners = (0..3 + i % 3).map(|_| (r.next_u64() % 257) as f64);
                vec![Val::L(corners.collect())]
            })
            .collect(),
        declared,
    }
}

type Layout = Vec<(&'static str, Kind)>;

/// Random value of a PLY type (within its range; floats exact in f32).
fn value_of(r: &mut Rng, ty: &str) -> f64 {
    match ty {
        "char" => r.range(-128.0, 127.0).round(),
        "uchar" => r.range(0.0, 255.0).round(),
        "short" => r.range(-32768.0, 32767.0).round(),
        "ushort" => r.range(0.0, 65535.0).round(),
        "int" | "int32" => r.range(-2e9, 2e9).round(),
        "uint" => r.range(0.0, 4e9).round(),
        "float" | "float32" => f64::from(r.range(-1e4, 1e4) as f32),
        _ => r.range(-1e6, 1e6),
    }
}

fn vertex_rows(r: &mut Rng, layout: &Layout, n: usize) -> Vec<Vec<Val>> {
    (0..n)
        .map(|_| {
            layout
                .iter()
                .map(|(_, k)| match k {
                    Kind::Scalar(t) => Val::S(value_of(r, t)),
                    Kind::List(_, t) => {
                        let len = (r.next_u64() % 5) as usize;
                        Val::L((0..len).map(|_| value_of(r, t)).collect())
                    }
                })
                .collect()
        })
        .collect()
}

fn column(layout: &Layout, rows: &[Vec<Val>], name: &str) -> Vec<f64> {
    let i = layout.iter().position(|(n, _)| *n == name).unwrap();
    rows.iter()
        .map(|row| match row[i] {
            Val::S(v) => v,
            Val::L(_) => panic!("list"),
        })
        .collect()
}

fn layouts() -> Vec<(Layout, bool)> {
    use Kind::{List, Scalar};
    vec![
        // Fixed-size records, every scalar type, normals scattered.
        (
            vec![
                ("red", Scalar("uchar")),
                ("x", Scalar("double")),
                ("nx", Scalar("float")),
                ("s", Scalar("short")),
                ("y", Scalar("float64")),
                ("ny", Scalar("float32")),
                ("u", Scalar("uint")),
                ("c", Scalar("char")),
                ("z", Scalar("double")),
                ("us", Scalar("ushort")),
                ("nz", Scalar("float")),
                ("i", Scalar("int32")),
            ],
            true,
        ),
        // A list inside the vertex: the general record path.
        (
            vec![
                ("ids", List("uchar", "int")),
                ("z", Scalar("float")),
                ("x", Scalar("int")),
                ("conf", Scalar("ushort")),
                ("y", Scalar("short")),
                ("more", List("int", "double")),
            ],
            false,
        ),
        // Integer coordinates of the small types; only two of three normals.
        (
            vec![
                ("y", Scalar("char")),
                ("nx", Scalar("float")),
                ("x", Scalar("uchar")),
                ("ny", Scalar("float")),
                ("z", Scalar("ushort")),
            ],
            false,
        ),
    ]
}

#[test]
fn odd_ply_layouts_in_all_encodings() {
    let d = tmp();
    for (li, (layout, has_normals)) in layouts().into_iter().enumerate() {
        for enc in [Enc::Ascii, Enc::Le, Enc::Be] {
            let seed = 1000 + li as u64;
            let mut r = Rng::new(seed);
            let cam = camera(&mut r);
            let rows = vertex_rows(&mut r, &layout, 257);
            let (xs, ys, zs) = (
                column(&layout, &rows, "x"),
                column(&layout, &rows, "y"),
                column(&layout, &rows, "z"),
            );
            let vertex = El {
                name: "vertex",
                props: layout.iter().map(|(n, k)| (*n, clone_kind(k))).collect(),
                rows,
                declared: None,
            };
            let mut els = vec![cam, vertex];
            if enc != Enc::Ascii {
                els.push(faces_after(&mut r, None));
            }
            let path = d.path().join(format!("odd{li}.ply"));
            std::fs::write(&path, build_ply(enc, &els)).unwrap();
            if enc != Enc::Ascii {
                // Faces declared but absent: the file is cut, even though
                // every vertex is there.
                let faces = els.len() - 1;
                els[faces] = faces_after(&mut r, Some(1000));
                let cut = d.path().join(format!("odd{li}_cut.ply"));
                std::fs::write(&cut, build_ply(enc, &els)).unwrap();
                let mut reader = open_reader(&cut, InvalidPolicy::Reject).unwrap();
                let mut chunk = scanmesh::io::PointChunk::default();
                let e = loop {
                    match reader.read_chunk(&mut chunk, DEFAULT_CHUNK) {
                        Ok(0) => panic!("layout {li}: faces cut short read as whole"),
                        Ok(_) => {}
                        Err(e) => break e.to_string(),
                    }
                };
                assert!(e.contains("element 'face': 1000 declared, 5 found"), "{e}");
            }
            for max in [1, 10, 300] {
                let back = read_all(&path, InvalidPolicy::Reject, max);
                let want: Vec<DVec3> = (0..257).map(|i| DVec3::new(xs[i], ys[i], zs[i])).collect();
                assert_eq!(back.xyz, want, "layout {li} seed {seed} max {max}");
                assert_eq!(back.normals.is_some(), has_normals, "layout {li}");
                if has_normals {
                    let v = &els[1];
                    let n: Vec<Vec3> = (0..257)
                        .map(|i| {
                            let [a, b, c] =
                                ["nx", "ny", "nz"].map(|k| column(&layout, &v.rows, k)[i] as f32);
                            Vec3::new(a, b, c)
                        })
                        .collect();
                    assert_eq!(back.normals.unwrap(), n, "layout {li} normals");
                }
            }
        }
    }
}

fn clone_kind(k: &Kind) -> Kind {
    match k {
        Kind::Scalar(t) => Kind::Scalar(t),
        Kind::List(c, t) => Kind::List(c, t),
    }
}

// ---- meshes --------------------------------------------------------------

fn write(d: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let p = d.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

/// A unit cube as 6 quads: 8 vertices, 12 triangles once fanned.
fn cube() -> (Vec<DVec3>, Vec<Vec<u32>>) {
    let v = (0..8)
        .map(|i| DVec3::new((i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64))
        .collect();
    let q = vec![
        vec![0, 2, 3, 1],
        vec![4, 5, 7, 6],
        vec![0, 1, 5, 4],
        vec![2, 6, 7, 3],
        vec![0, 4, 6, 2],
        vec![1, 3, 7, 5],
    ];
    (v, q)
}

fn fan(q: &[Vec<u32>]) -> Vec<[u32; 3]> {
    q.iter()
        .flat_map(|p| (1..p.len() - 1).map(move |k| [p[0], p[k], p[k + 1]]))
        .collect()
}

fn cube_ply(enc: Enc, faces_first: bool) -> Vec<u8> {
    let (v, q) = cube();
    let vertex = El {
        name: "vertex",
        props: vec![
            ("x", Kind::Scalar("float")),
            ("y", Kind::Scalar("double")),
            ("z", Kind::Scalar("int")),
        ],
        rows: v
            .iter()
            .map(|p| vec![Val::S(p.x), Val::S(p.y), Val::S(p.z)])
            .collect(),
        declared: None,
    };
    let face = El {
        name: "face",
        props: vec![
            ("flags", Kind::Scalar("uchar")),
            ("vertex_indices", Kind::List("uchar", "uint")),
        ],
        rows: q
            .iter()
            .map(|p| vec![Val::S(3.0), Val::L(p.iter().map(|&i| i as f64).collect())])
            .collect(),
        declared: None,
    };
    let mut r = Rng::new(5);
    let mut els = vec![camera(&mut r), vertex, face];
    if faces_first {
        els.swap(1, 2);
    }
    build_ply(enc, &els)
}

#[test]
fn ply_meshes_fan_triangulated() {
    let d = tmp();
    let (v, q) = cube();
    for enc in [Enc::Ascii, Enc::Le, Enc::Be] {
        for faces_first in [false, true] {
            let p = write(d.path(), "cube.ply", &cube_ply(enc, faces_first));
            let (verts, tris) = read_mesh(&p).unwrap();
            assert_eq!(verts, v);
            assert_eq!(tris, fan(&q));
            assert_eq!(read_mesh_any(&p).unwrap(), (verts, tris));
        }
    }
}

#[test]
fn obj_meshes_with_slashes_and_negative_indices() {
    let d = tmp();
    let (v, q) = cube();
    let mut s = String::from("# cube\nmtllib x.mtl\no cube\n");
    for p in &v {
        s += &format!("v {} {} {}\nvn 0 0 1\nvt 0 0\n", p.x, p.y, p.z);
    }
    // Mixed corner forms; the last face uses relative indices.
    for (k, f) in q.iter().enumerate() {
        s += "f";
        for (j, &i) in f.iter().enumerate() {
            s += &match (k == q.len() - 1, j % 3) {
                (true, _) => format!(" {}", i as i64 - 8),
                (_, 0) => format!(" {}", i + 1),
                (_, 1) => format!(" {}/{}", i + 1, i + 1),
                _ => format!(" {}/{}/{}", i + 1, 1, i + 1),
            };
        }
        s += "\n";
    }
    s += "f 1//1 2//2 3//3\n";
    let p = write(d.path(), "cube.obj", s.as_bytes());
    let mut want = fan(&q);
    want.push([0, 1, 2]);
    let (verts, tris) = read_obj_mesh(&p).unwrap();
    assert_eq!((verts.clone(), tris.clone()), (v, want));
    assert_eq!(read_mesh_any(&p).unwrap(), (verts.clone(), tris.clone()));
    let gz = d.path().join("cube.obj.gz");
    gzip_file(&p, &gz, 1);
    assert_eq!(read_mesh_any(&gz).unwrap(), (verts, tris));
}

/// The Stanford dragon (437,645 vertices, 871,414 triangles) as shipped.
#[test]
fn dragon_ground_truth_mesh() {
    let path = Path::new("/work/shared/data/dragon_vrip.ply.gz");
    if !path.exists() {
        eprintln!("skipping: {} not present", path.display());
        return;
    }
    let (v, t) = read_mesh(path).unwrap();
    assert_eq!((v.len(), t.len()), (437_645, 871_414));
    let n = v.len() as u32;
    assert!(t.iter().flatten().all(|&i| i < n));
    let back = read_all(path, InvalidPolicy::Reject, DEFAULT_CHUNK);
    assert_eq!(back.xyz, v);
}

// ---- checked-in fixtures -----------------------------------------------

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name)
}

#[test]
fn fixture_ascii_with_comments_and_extra_properties() {
    let back = read_all(
        &fixture("ascii_comments.ply"),
        InvalidPolicy::Reject,
        DEFAULT_CHUNK,
    );
    // The fixture's vertices are (i, 2i, -i/4) with normal +z, i = 0..5.
    let want: Vec<DVec3> = (0..5)
        .map(|i| DVec3::new(i as f64, 2.0 * i as f64, -(i as f64) / 4.0))
        .collect();
    assert_eq!(back.xyz, want);
    assert_eq!(back.normals.unwrap(), vec![Vec3::Z; 5]);
    let (v, t) = read_mesh(&fixture("ascii_comments.ply")).unwrap();
    assert_eq!(v, want);
    assert_eq!(t, vec![[0, 1, 2], [0, 2, 3], [2, 3, 4]]);
}

#[test]
fn fixture_csv_with_header() {
    let back = read_all(&fixture("header.csv"), InvalidPolicy::Reject, 2);
    // Rows are (i + 0.5, -i, 10 i) with normal (0, 1, 0), i = 0..4.
    let want: Vec<DVec3> = (0..4)
        .map(|i| DVec3::new(i as f64 + 0.5, -(i as f64), 10.0 * i as f64))
        .collect();
    assert_eq!(back.xyz, want);
    assert_eq!(back.normals.unwrap(), vec![Vec3::Y; 4]);
}

#[test]
fn fixture_big_endian_binary() {
    let path = fixture("big_endian.ply");
    let r = open_reader(&path, InvalidPolicy::Reject).unwrap();
    assert_eq!(r.info().format, Format::PlyBinaryBe);
    drop(r);
    let back = read_all(&path, InvalidPolicy::Reject, 3);
    // Vertices are (i * 0.5, 100 - i, i^2) for i = 0..6, after one camera.
    let want: Vec<DVec3> = (0..6)
        .map(|i| DVec3::new(i as f64 * 0.5, 100.0 - i as f64, (i * i) as f64))
        .collect();
    assert_eq!(back.xyz, want);
    assert!(back.normals.is_none());
}
