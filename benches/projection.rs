//! Local-projection triangulation (paper 2) through the pipeline: the
//! whole job (planes, growth, seam re-growth, streaming output; normals
//! are the kernel's own) on a noisy 1M-point torus in two tiles, as the
//! default plan tiles 1M points, and on 327k points (paper 2's hand-bones
//! size) in one tile. Two threads.

mod common;

use common::torus_store;
use criterion::{criterion_group, criterion_main, Criterion};
use scanmesh::io::memory::MemoryReader;
use scanmesh::mesh::MeshFormat;
use scanmesh::pipeline::{NoProgress, RunOptions};
use scanmesh::recon::projection::{reconstruct_projection, ProjectionParams};
use scanmesh::store::{build_store, BuildOptions, PointStore, TileTarget};
use scanmesh::synth::{generate, Shape};
use std::hint::black_box;
use std::path::Path;

fn mesh(store: &mut PointStore, out: &Path) {
    black_box(
        reconstruct_projection(
            store,
            &ProjectionParams::default(),
            out,
            MeshFormat::PlyBinary,
            RunOptions::new(2),
            &NoProgress,
        )
        .expect("reconstruct"),
    );
}

fn hand_bones_size(dir: &Path) -> PointStore {
    let scan = generate(&Shape::torus(1.0, 0.3), 327_000, 0.0002, 2).expect("generate");
    let mut reader = MemoryReader::new("torus", scan.points, None);
    let opts = BuildOptions {
        tiles: TileTarget::Points(u64::MAX),
        ..BuildOptions::default()
    };
    build_store(&mut reader, dir, &opts, &NoProgress).expect("store")
}

fn bench(c: &mut Criterion) {
    let dir = tempfile::tempdir().expect("tmp");
    let out = dir.path().join("mesh.ply");
    let mut million = torus_store(&dir.path().join("1m"), 500_000);
    let mut small = hand_bones_size(&dir.path().join("327k"));
    let mut g = c.benchmark_group("projection");
    g.sample_size(10);
    g.bench_function("torus_1M_2_tiles", |b| b.iter(|| mesh(&mut million, &out)));
    g.bench_function("torus_327k", |b| b.iter(|| mesh(&mut small, &out)));
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
