//! Implicit reconstruction through the pipeline (paper 1 sections 2.5-2.6)
//! on a noisy 1M-point torus: marching cubes from stored normals, untiled
//! and tiled, and the whole job (normals + orientation + marching cubes).

mod common;

use common::torus_store;
use criterion::{criterion_group, criterion_main, BatchSize, Criterion};
use scanmesh::mesh::MeshFormat;
use scanmesh::normals::compute_normals;
use scanmesh::pipeline::{NoProgress, RunOptions};
use scanmesh::recon::implicit::reconstruct::{reconstruct_implicit, ImplicitParams};
use scanmesh::store::PointStore;
use std::hint::black_box;
use std::path::Path;

fn mesh(store: &mut PointStore, out: &Path) {
    let params = ImplicitParams::default();
    let opts = RunOptions::new(2);
    black_box(
        reconstruct_implicit(
            store,
            &params,
            out,
            MeshFormat::PlyBinary,
            opts,
            &NoProgress,
        )
        .expect("reconstruct"),
    );
}

fn bench(c: &mut Criterion) {
    let dir = tempfile::tempdir().expect("tmp");
    let out = dir.path().join("mesh.ply");
    let params = ImplicitParams::default();
    let mut whole = torus_store(&dir.path().join("whole"), u64::MAX);
    let mut tiled = torus_store(&dir.path().join("tiled"), 150_000);
    for s in [&mut whole, &mut tiled] {
        compute_normals(s, &params.normals, RunOptions::new(2), &NoProgress).expect("normals");
    }
    let mut g = c.benchmark_group("reconstruct_1M");
    g.sample_size(10);
    g.bench_function("marching_cubes", |b| b.iter(|| mesh(&mut whole, &out)));
    g.bench_function("marching_cubes_tiled", |b| {
        b.iter(|| mesh(&mut tiled, &out))
    });
    // The store is rebuilt outside the timed part, so each run computes the
    // normals afresh.
    g.bench_function("normals_and_marching_cubes", |b| {
        b.iter_batched(
            || {
                let fresh = tempfile::tempdir().expect("tmp");
                let s = torus_store(fresh.path(), u64::MAX);
                (fresh, s)
            },
            |(_fresh, mut s)| mesh(&mut s, &out),
            BatchSize::PerIteration,
        )
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
