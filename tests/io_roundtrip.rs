//! Round trips through every writer and reader (exact for PLY and XYZ,
//! within half a quantum for LAS/LAZ), gzip input and chunk boundaries.

mod common;

use common::read_all;
use flate2::write::GzEncoder;
use flate2::Compression;
use glam::{DVec3, Vec3};
use scanmesh::geom::Aabb;
use scanmesh::io::write::choose_las_transform;
use scanmesh::io::{
    create_writer, open_reader, Format, InvalidPolicy, LasTransform, PointChunk, WriterSpec,
    DEFAULT_CHUNK,
};
use scanmesh::synth::Rng;
use std::io::Write;
use std::path::Path;

struct Cloud {
    xyz: Vec<DVec3>,
    normals: Vec<Vec3>,
    flags: Vec<u8>,
}

/// Points spread over a UTM-like box (large offsets, full f64 mantissas).
fn cloud(n: usize, seed: u64) -> Cloud {
    let mut r = Rng::new(seed);
    let xyz = (0..n)
        .map(|_| {
            DVec3::new(
                r.range(5e5, 5.02e5),
                r.range(4.2e6, 4.2e6 + 3e3),
                r.range(-50.0, 400.0),
            )
        })
        .collect();
    let normals = (0..n)
        .map(|_| {
            Vec3::new(
                r.range(-1.0, 1.0) as f32,
                r.range(-1.0, 1.0) as f32,
                r.range(-1.0, 1.0) as f32,
            )
            .normalize_or(Vec3::Z)
        })
        .collect();
    let flags = (0..n).map(|_| r.next_u64() as u8).collect();
    Cloud {
        xyz,
        normals,
        flags,
    }
}

fn bounds(c: &Cloud) -> Aabb {
    let mut b = Aabb::EMPTY;
    c.xyz.iter().for_each(|&p| b.add(p));
    b
}

fn spec(format: Format, with_normals: bool, with_flags: bool, b: Option<Aabb>) -> WriterSpec {
    WriterSpec {
        format,
        with_normals,
        with_flags,
        bounds: b,
        las_transform: None,
        attributes: Default::default(),
        ..WriterSpec::new(format)
    }
}

/// Writes `c` in chunks of `step` points.
fn write_cloud(path: &Path, spec: &WriterSpec, c: &Cloud, step: usize) -> u64 {
    let mut w = create_writer(path, spec).unwrap();
    for start in (0..c.xyz.len()).step_by(step) {
        let end = (start + step).min(c.xyz.len());
        let chunk = PointChunk {
            first_index: start as u64,
            xyz: c.xyz[start..end].to_vec(),
            normals: Some(c.normals[start..end].to_vec()),
            indices: None,
            attrs: Default::default(),
            ..PointChunk::default()
        };
        w.write_chunk(&chunk, Some(&c.flags[start..end])).unwrap();
    }
    w.finish().unwrap()
}

fn tmp() -> tempfile::TempDir {
    tempfile::tempdir().unwrap()
}

#[test]
fn exact_formats_round_trip() {
    let seed = 0x5EED_0001;
    let c = cloud(1234, seed);
    let d = tmp();
    let cases = [
        (Format::PlyBinaryLe, "a.ply"),
        (Format::PlyBinaryBe, "b.ply"),
        (Format::PlyAscii, "c.ply"),
        (Format::Xyz, "d.xyz"),
        (Format::Pcd, "e.pcd"),
    ];
    for (format, name) in cases {
        for with_flags in [false, true] {
            let path = d.path().join(name);
            let n = write_cloud(&path, &spec(format, true, with_flags, None), &c, 100);
            assert_eq!(n, 1234);
            let back = read_all(&path, InvalidPolicy::Reject, 333);
            assert_eq!(
                back.xyz, c.xyz,
                "seed {seed:#x} {format:?} flags {with_flags}"
            );
            assert_eq!(
                back.normals.as_ref(),
                Some(&c.normals),
                "seed {seed:#x} {format:?}"
            );
            assert_eq!(back.indices, (0..1234).collect::<Vec<u64>>());
            let r = open_reader(&path, InvalidPolicy::Reject).unwrap();
            let want = if format == Format::Xyz {
                None
            } else {
                Some(1234)
            };
            assert_eq!(r.info().declared_count, want);
            if format != Format::Xyz {
                assert_eq!(r.info().format, format);
            }
        }
        // Without normals the reader must not invent any.
        let path = d.path().join(name);
        write_cloud(&path, &spec(format, false, false, None), &c, 1000);
        let back = read_all(&path, InvalidPolicy::Reject, DEFAULT_CHUNK);
        assert_eq!(back.xyz, c.xyz, "seed {seed:#x} {format:?} no normals");
        assert!(back.normals.is_none());
    }
}

#[test]
fn binary_ply_flags_are_written() {
    let c = cloud(10, 7);
    let d = tmp();
    let path = d.path().join("f.ply");
    write_cloud(&path, &spec(Format::PlyBinaryLe, false, true, None), &c, 4);
    let bytes = std::fs::read(&path).unwrap();
    let body = &bytes[bytes
        .windows(11)
        .position(|w| w == b"end_header\n")
        .unwrap()
        + 11..];
    assert_eq!(body.len(), 10 * 25);
    let flags: Vec<u8> = body.chunks(25).map(|r| r[24]).collect();
    assert_eq!(flags, c.flags);
}

/// Largest distance between written and read LAS coordinates, per axis.
fn las_error(a: &[DVec3], b: &[DVec3]) -> DVec3 {
    a.iter()
        .zip(b)
        .fold(DVec3::ZERO, |m, (p, q)| m.max((*p - *q).abs()))
}

/// Half a quantum, plus the rounding of `xi * scale + offset` in f64 (a few
/// ulps of the largest coordinate).
fn las_tolerance(t: &LasTransform, pts: &[DVec3]) -> DVec3 {
    let big = pts.iter().fold(DVec3::ZERO, |m, p| m.max(p.abs()));
    t.scale * 0.5 + big * 4.0 * f64::EPSILON
}

#[test]
fn las_and_laz_round_trip_within_half_quantum() {
    let seed = 0x1A5;
    let c = cloud(70_001, seed);
    let b = bounds(&c);
    let d = tmp();
    for (format, name) in [(Format::Las, "p.las"), (Format::Laz, "p.laz")] {
        let path = d.path().join(name);
        let n = write_cloud(&path, &spec(format, false, true, Some(b)), &c, 9999);
        assert_eq!(n, 70_001);
        let r = open_reader(&path, InvalidPolicy::Reject).unwrap();
        let info = r.info().clone();
        drop(r);
        assert_eq!(info.format, format);
        assert_eq!(info.declared_count, Some(70_001));
        let t = info.las_transform.unwrap();
        assert_eq!(Some(t), choose_las_transform(&b));
        let hb = info.header_bounds.unwrap();
        assert!(hb.expanded(t.scale.x).contains(b.min) && hb.expanded(t.scale.x).contains(b.max));
        let back = read_all(&path, InvalidPolicy::Reject, 4096);
        assert_eq!(back.xyz.len(), c.xyz.len());
        let err = las_error(&back.xyz, &c.xyz);
        let tol = las_tolerance(&t, &c.xyz);
        assert!(
            err.cmple(tol).all(),
            "seed {seed:#x} {format:?}: err {err} > {tol}"
        );
        // LAS -> PLY -> LAS keeps the quantised values exactly.
        let ply = d.path().join(format!("{name}.ply"));
        let mut w = create_writer(&ply, &spec(Format::PlyBinaryLe, false, false, None)).unwrap();
        let chunk = PointChunk {
            xyz: back.xyz.clone(),
            ..Default::default()
        };
        w.write_chunk(&chunk, None).unwrap();
        w.finish().unwrap();
        assert_eq!(read_all(&ply, InvalidPolicy::Reject, 777).xyz, back.xyz);
    }
}

#[test]
fn las_uses_given_transform() {
    let c = cloud(500, 3);
    let t = LasTransform {
        scale: DVec3::new(0.01, 0.02, 0.005),
        offset: DVec3::new(5e5, 4.2e6, 0.0),
    };
    let d = tmp();
    let path = d.path().join("t.las");
    let mut s = spec(Format::Las, false, false, None);
    s.las_transform = Some(t);
    write_cloud(&path, &s, &c, 64);
    let r = open_reader(&path, InvalidPolicy::Reject).unwrap();
    assert_eq!(r.info().las_transform, Some(t));
    drop(r);
    let back = read_all(&path, InvalidPolicy::Reject, 100);
    let err = las_error(&back.xyz, &c.xyz);
    assert!(err.cmple(las_tolerance(&t, &c.xyz)).all(), "err {err}");
}

#[test]
fn chosen_las_transform_fits_with_headroom() {
    let mut r = Rng::new(99);
    for case in 0..200 {
        let c = DVec3::new(r.range(-1e7, 1e7), r.range(-1e7, 1e7), r.range(-1e3, 1e3));
        let e = DVec3::new(r.range(0.0, 1e5), r.range(0.0, 1.0), r.range(0.0, 1e-3));
        let b = Aabb::new(c - e, c + e);
        let t = choose_las_transform(&b).unwrap();
        let reach = (b.max - t.offset).abs().max((b.min - t.offset).abs()) / t.scale;
        assert!(
            reach.max_element() <= (1u64 << 30) as f64,
            "case {case}: {reach}"
        );
        // A tenth of the scale would not fit (the scale is the finest), unless
        // the floor of 1e-9 was hit.
        let finer = reach.max_element() * 10.0;
        assert!(
            finer > (1u64 << 30) as f64 || t.scale.x <= 1e-9 * 1.0001,
            "case {case}"
        );
        assert_eq!(t.offset, t.offset.round());
    }
}

#[test]
fn chunk_boundaries_do_not_matter() {
    let c = cloud(1001, 11);
    let d = tmp();
    for (format, name) in [
        (Format::PlyBinaryLe, "a.ply"),
        (Format::PlyAscii, "b.ply"),
        (Format::Xyz, "c.xyz"),
        (Format::Las, "d.las"),
    ] {
        let path = d.path().join(name);
        let normals = format != Format::Las;
        write_cloud(
            &path,
            &spec(format, normals, false, Some(bounds(&c))),
            &c,
            1001,
        );
        let whole = read_all(&path, InvalidPolicy::Reject, DEFAULT_CHUNK);
        assert_eq!(whole.chunks, 1, "{format:?}");
        for max in [0, 1, 7, 1000, 1001, 1002] {
            let back = read_all(&path, InvalidPolicy::Reject, max);
            assert_eq!(back.xyz, whole.xyz, "{format:?} max {max}");
            assert_eq!(back.normals, whole.normals, "{format:?} max {max}");
            assert_eq!(
                back.chunks,
                1001usize.div_ceil(max.max(1)),
                "{format:?} {max}"
            );
        }
    }
}

// ---- gzip --------------------------------------------------------------

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

#[test]
fn gzip_input_is_transparent() {
    let c = cloud(3000, 21);
    let d = tmp();
    for (format, name, gz_name) in [
        (Format::PlyBinaryLe, "g.ply", "g.ply.gz"),
        (Format::PlyAscii, "h.ply", "h.ply.gz"),
        (Format::Xyz, "g.xyz", "g.xyz.gz"),
        // Content decides, not the name: a gzipped PLY without `.gz`.
        (Format::PlyBinaryBe, "i.ply", "i-gz.ply"),
    ] {
        let plain = d.path().join(name);
        write_cloud(&plain, &spec(format, true, false, None), &c, 512);
        for members in [1, 3] {
            let gz = d.path().join(gz_name);
            gzip_file(&plain, &gz, members);
            let r = open_reader(&gz, InvalidPolicy::Reject).unwrap();
            assert!(r.info().gzip, "{gz_name}");
            drop(r);
            let back = read_all(&gz, InvalidPolicy::Reject, 1000);
            assert_eq!(back.xyz, c.xyz, "{gz_name} members {members}");
            assert_eq!(back.normals.unwrap(), c.normals, "{gz_name}");
        }
    }
}
