//! Ingest throughput: 200k points written once as binary PLY, ASCII PLY and
//! XYZ (with normals), then each read fully through `open_reader` with
//! `DEFAULT_CHUNK`.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use glam::{DVec3, Vec3};
use scanmesh::io::{
    create_writer, open_reader, Format, InvalidPolicy, PointChunk, WriterSpec, DEFAULT_CHUNK,
};
use std::hint::black_box;
use std::path::Path;

const N: usize = 200_000;

/// A seeded cloud (SplitMix64), normals on the unit sphere.
fn cloud() -> PointChunk {
    let mut s = 0x001D_6E57_u64;
    let mut next = || {
        s = s.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = s;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut xyz = Vec::with_capacity(N);
    let mut normals = Vec::with_capacity(N);
    for _ in 0..N {
        xyz.push(DVec3::new(
            5e5 + 200.0 * next(),
            4.2e6 + 200.0 * next(),
            30.0 * next(),
        ));
        let n = Vec3::new(
            next() as f32 - 0.5,
            next() as f32 - 0.5,
            next() as f32 - 0.5,
        );
        normals.push(n.normalize_or(Vec3::Z));
    }
    PointChunk {
        first_index: 0,
        xyz,
        normals: Some(normals),
        indices: None,
        attrs: Default::default(),
        ..PointChunk::default()
    }
}

fn write(path: &Path, format: Format, points: &PointChunk) {
    let spec = WriterSpec {
        with_normals: true,
        ..WriterSpec::new(format)
    };
    let mut w = create_writer(path, &spec).expect("create");
    w.write_chunk(points, None).expect("write");
    w.finish().expect("finish");
}

fn read_fully(path: &Path) -> usize {
    let mut r = open_reader(path, InvalidPolicy::Reject).expect("open");
    let mut chunk = PointChunk::default();
    let mut total = 0;
    loop {
        let n = r.read_chunk(&mut chunk, DEFAULT_CHUNK).expect("read");
        if n == 0 {
            return total;
        }
        total += n;
        black_box(&chunk.xyz);
    }
}

fn ingest(c: &mut Criterion) {
    let dir = tempfile::tempdir().expect("tempdir");
    let points = cloud();
    let files = [
        ("binary_ply", Format::PlyBinaryLe, "p.ply"),
        ("ascii_ply", Format::PlyAscii, "a.ply"),
        ("xyz", Format::Xyz, "x.xyz"),
    ];
    let mut group = c.benchmark_group("ingest_200k");
    group.throughput(Throughput::Elements(N as u64));
    group.sample_size(10);
    for (name, format, file) in files {
        let path = dir.path().join(file);
        write(&path, format, &points);
        assert_eq!(read_fully(&path), N);
        group.bench_function(name, |b| b.iter(|| read_fully(&path)));
    }
    group.finish();
}

criterion_group!(benches, ingest);
criterion_main!(benches);
