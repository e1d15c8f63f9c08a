//! Streaming mesh writer: round trips through small independent PLY/OBJ
//! parsers, header counts, atomic appearance, and errors that name the file.

use glam::{DVec2, DVec3};
use scanmesh::mesh::{shapes, write_mesh, Mesh, MeshError, MeshFormat, MeshWriter, WriteOptions};
use std::path::Path;

/// A PLY file as read back: the header's declared counts and the data.
struct Ply {
    declared_vertices: u64,
    declared_faces: u64,
    vertex_type: String,
    mesh: Mesh,
}

/// Minimal PLY reader for exactly what the writer promises: ascii or
/// binary_little_endian, vertex x y z (float or double), face list uchar int.
fn parse_ply(bytes: &[u8]) -> Ply {
    let end = b"end_header\n";
    let header_len = bytes
        .windows(end.len())
        .position(|w| w == end)
        .expect("end_header")
        + end.len();
    let header = std::str::from_utf8(&bytes[..header_len]).expect("ascii header");
    let mut lines = header.lines();
    assert_eq!(lines.next(), Some("ply"));
    let (mut format, mut nv, mut nf, mut vtype) = (String::new(), 0u64, 0u64, String::new());
    for line in lines {
        let tok: Vec<&str> = line.split_whitespace().collect();
        match tok.as_slice() {
            ["format", f, "1.0"] => format = f.to_string(),
            ["element", "vertex", n] => nv = n.parse().expect("vertex count"),
            ["element", "face", n] => nf = n.parse().expect("face count"),
            ["property", t, "x"] => vtype = t.to_string(),
            ["property", "list", "uchar", "int", "vertex_indices"] => {}
            ["property", _, "y" | "z"] | ["comment", ..] | ["end_header"] => {}
            other => panic!("unexpected header line {other:?}"),
        }
    }
    let body = &bytes[header_len..];
    let mesh = match format.as_str() {
        "ascii" => parse_ascii_body(
            std::str::from_utf8(body).expect("utf8"),
            nv,
            nf,
            vtype == "float",
        ),
        "binary_little_endian" => parse_binary_body(body, nv, nf, vtype == "float"),
        f => panic!("format {f}"),
    };
    Ply {
        declared_vertices: nv,
        declared_faces: nf,
        vertex_type: vtype,
        mesh,
    }
}

fn parse_ascii_body(body: &str, nv: u64, nf: u64, single: bool) -> Mesh {
    let mut lines = body.lines();
    let mut m = Mesh::default();
    // A "float" property is read as f32, as a typed reader would.
    let scalar = |t: &str| {
        if single {
            t.parse::<f32>().unwrap() as f64
        } else {
            t.parse::<f64>().unwrap()
        }
    };
    for _ in 0..nv {
        let c: Vec<f64> = lines
            .next()
            .expect("vertex line")
            .split(' ')
            .map(scalar)
            .collect();
        m.vertices.push(DVec3::new(c[0], c[1], c[2]));
    }
    for _ in 0..nf {
        let c: Vec<u32> = lines
            .next()
            .expect("face line")
            .split(' ')
            .map(|t| t.parse().unwrap())
            .collect();
        assert_eq!(c[0], 3);
        m.triangles.push([c[1], c[2], c[3]]);
    }
    assert_eq!(lines.next(), None, "trailing data");
    m
}

fn parse_binary_body(body: &[u8], nv: u64, nf: u64, single: bool) -> Mesh {
    let width = if single { 4 } else { 8 };
    assert_eq!(body.len() as u64, nv * 3 * width + nf * 13, "body size");
    let (verts, faces) = body.split_at((nv * 3 * width) as usize);
    let scalar = |b: &[u8]| {
        if single {
            f32::from_le_bytes(b.try_into().unwrap()) as f64
        } else {
            f64::from_le_bytes(b.try_into().unwrap())
        }
    };
    let coords: Vec<f64> = verts.chunks(width as usize).map(scalar).collect();
    let vertices = coords
        .chunks(3)
        .map(|c| DVec3::new(c[0], c[1], c[2]))
        .collect();
    let triangles = faces
        .chunks(13)
        .map(|f| {
            assert_eq!(f[0], 3);
            let i =
                |k: usize| i32::from_le_bytes(f[1 + 4 * k..5 + 4 * k].try_into().unwrap()) as u32;
            [i(0), i(1), i(2)]
        })
        .collect();
    Mesh::new(vertices, triangles)
}

fn parse_obj(text: &str) -> Mesh {
    let mut m = Mesh::default();
    for line in text.lines() {
        let tok: Vec<&str> = line.split_whitespace().collect();
        match tok.as_slice() {
            ["v", x, y, z] => m.vertices.push(DVec3::new(
                x.parse().unwrap(),
                y.parse().unwrap(),
                z.parse().unwrap(),
            )),
            ["f", a, b, c] => m
                .triangles
                .push([a, b, c].map(|s| s.parse::<u32>().unwrap() - 1)),
            ["#", ..] => {}
            other => panic!("unexpected OBJ line {other:?}"),
        }
    }
    m
}

/// A mesh whose coordinates need all 17 significant digits.
fn awkward_mesh(seed: u64) -> Mesh {
    let mut m = shapes::icosphere(2);
    let mut s = seed;
    for p in &mut m.vertices {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        *p = *p * 1234.5678
            + DVec3::splat((s >> 11) as f64 / (1u64 << 53) as f64)
            + DVec3::new(5e5, -3e6, 1e-9);
    }
    m
}

fn read_back(path: &Path, format: MeshFormat) -> Mesh {
    let bytes = std::fs::read(path).unwrap();
    match format {
        MeshFormat::Obj => parse_obj(std::str::from_utf8(&bytes).unwrap()),
        _ => {
            let ply = parse_ply(&bytes);
            assert_eq!(ply.declared_vertices, ply.mesh.vertices.len() as u64);
            assert_eq!(ply.declared_faces, ply.mesh.triangles.len() as u64);
            ply.mesh
        }
    }
}

const FORMATS: [MeshFormat; 3] = [MeshFormat::PlyBinary, MeshFormat::PlyAscii, MeshFormat::Obj];

#[test]
fn every_format_round_trips_exactly() {
    let seed = 42;
    let mesh = awkward_mesh(seed);
    let dir = tempfile::tempdir().unwrap();
    for format in FORMATS {
        let path = dir.path().join(format!("out-{format:?}.mesh"));
        let counts = write_mesh(&path, &mesh, format).unwrap().counts();
        assert_eq!(
            counts,
            (mesh.vertices.len() as u64, mesh.triangles.len() as u64)
        );
        assert_eq!(read_back(&path, format), mesh, "seed {seed}, {format:?}");
    }
}

#[test]
fn tiles_stream_in_batches_with_global_indices() {
    let whole = shapes::grid(6, 4, DVec2::new(3.0, 2.0));
    let dir = tempfile::tempdir().unwrap();
    for format in FORMATS {
        let path = dir.path().join(format!("tiles-{format:?}"));
        let mut w = MeshWriter::create(&path, format).unwrap();
        // Vertices in three uneven batches; faces in two, one written
        // before all the vertices it uses exist.
        let first = w.add_vertices(&whole.vertices[..7]).unwrap();
        w.add_triangles(&whole.triangles[..9]).unwrap();
        assert_eq!(first, 0);
        assert_eq!(w.add_vertices(&whole.vertices[7..20]).unwrap(), 7);
        assert_eq!(w.add_vertices(&whole.vertices[20..]).unwrap(), 20);
        w.add_triangles(&whole.triangles[9..]).unwrap();
        assert!(!path.exists(), "nothing under the final name before finish");
        assert_eq!(w.finish().unwrap().counts(), (35, 48));
        assert_eq!(read_back(&path, format), whole, "{format:?}");
    }
}

#[test]
fn header_counts_are_patched_in_fixed_width() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = shapes::icosphere(1);
    let path = dir.path().join("counts.ply");
    write_mesh(&path, &mesh, MeshFormat::PlyBinary).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let ply = parse_ply(&bytes);
    assert_eq!((ply.declared_vertices, ply.declared_faces), (42, 80));
    assert_eq!(ply.vertex_type, "double");
    // The header is the same length whatever the counts.
    let empty = dir.path().join("empty.ply");
    write_mesh(&empty, &Mesh::default(), MeshFormat::PlyBinary).unwrap();
    let empty_len = std::fs::metadata(&empty).unwrap().len();
    assert_eq!(bytes.len() as u64, empty_len + 42 * 24 + 80 * 13);
    let ply = parse_ply(&std::fs::read(&empty).unwrap());
    assert_eq!((ply.declared_vertices, ply.declared_faces), (0, 0));
}

#[test]
fn single_precision_writes_floats() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = awkward_mesh(7);
    for format in FORMATS {
        let path = dir.path().join(format!("f32-{format:?}"));
        let mut w = MeshWriter::create_with(
            &path,
            format,
            WriteOptions {
                single_precision: true,
            },
        )
        .unwrap();
        w.add_vertices(&mesh.vertices).unwrap();
        w.add_triangles(&mesh.triangles).unwrap();
        w.finish().unwrap();
        let got = read_back(&path, format);
        // OBJ has no types: its text must read back to the same f32.
        let as_f32 = |v: &[DVec3]| v.iter().map(|p| p.as_vec3()).collect::<Vec<_>>();
        assert!(
            as_f32(&got.vertices) == as_f32(&mesh.vertices),
            "{format:?}"
        );
        assert_eq!(got.triangles, mesh.triangles);
        if format == MeshFormat::PlyBinary {
            assert_eq!(
                parse_ply(&std::fs::read(&path).unwrap()).vertex_type,
                "float"
            );
        }
    }
}

fn assert_empty(dir: &Path) {
    let left: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert!(left.is_empty(), "left behind: {left:?}");
}

#[test]
fn dropped_writer_leaves_no_file() {
    let dir = tempfile::tempdir().unwrap();
    for format in FORMATS {
        let mut w = MeshWriter::create(&dir.path().join("dropped.ply"), format).unwrap();
        w.add_vertices(&[DVec3::ZERO, DVec3::X, DVec3::Y]).unwrap();
        w.add_triangles(&[[0, 1, 2]]).unwrap();
        drop(w);
        assert_empty(dir.path());
    }
}

#[test]
fn dangling_index_fails_and_leaves_no_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("dangling.obj");
    let mut w = MeshWriter::create(&path, MeshFormat::Obj).unwrap();
    w.add_vertices(&[DVec3::ZERO, DVec3::X, DVec3::Y]).unwrap();
    w.add_triangles(&[[0, 1, 2], [1, 2, 3], [0, 2, 1]]).unwrap();
    match w.finish() {
        Err(MeshError::DanglingIndex {
            triangle: 1,
            index: 3,
            vertex_count: 3,
            ..
        }) => {}
        other => panic!("expected a dangling index, got {other:?}"),
    }
    assert_empty(dir.path());
}

#[test]
fn unwritable_path_errors_naming_the_path() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("no-such-dir").join("out.ply");
    let err = MeshWriter::create(&path, MeshFormat::PlyBinary)
        .err()
        .expect("must fail");
    let text = err.to_string();
    assert!(text.contains(&*path.to_string_lossy()), "{text}");
    let err = write_mesh(&path, &shapes::icosphere(0), MeshFormat::Obj).unwrap_err();
    assert!(err.to_string().contains("out.ply"), "{err}");
}

#[test]
fn non_finite_vertex_is_refused_with_the_path() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("nan.ply");
    let mut w = MeshWriter::create(&path, MeshFormat::PlyAscii).unwrap();
    let err = w
        .add_vertices(&[DVec3::ZERO, DVec3::new(0.0, f64::INFINITY, 0.0)])
        .unwrap_err();
    assert!(
        matches!(err, MeshError::NonFiniteOutput { vertex: 1, .. }),
        "{err:?}"
    );
    assert!(err.to_string().contains("nan.ply"), "{err}");
    drop(w);
    assert_empty(dir.path());
}
