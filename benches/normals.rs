//! Normals end to end through the pipeline (store already built): PCA only,
//! and PCA + spanning-tree orientation, on a noisy torus, untiled and tiled.

mod common;

use common::torus_store;
use criterion::{criterion_group, criterion_main, Criterion};
use scanmesh::normals::{compute_normals, NormalParams, Orientation};
use scanmesh::pipeline::{NoProgress, RunOptions};
use scanmesh::spatial::KnnBackend;
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let dir = tempfile::tempdir().expect("tmp");
    let mut whole = torus_store(&dir.path().join("whole"), u64::MAX);
    let mut tiled = torus_store(&dir.path().join("tiled"), 150_000);
    let mut g = c.benchmark_group("normals_1M");
    g.sample_size(10);
    for backend in [KnnBackend::Grid, KnnBackend::KdTree] {
        let pca = NormalParams {
            backend,
            orientation: Orientation::None,
            ..NormalParams::default()
        };
        let mst = NormalParams {
            backend,
            ..NormalParams::default()
        };
        g.bench_function(format!("pca_only/{backend:?}"), |b| {
            b.iter(|| {
                black_box(
                    compute_normals(&mut whole, &pca, RunOptions::new(2), &NoProgress)
                        .expect("normals"),
                )
            })
        });
        g.bench_function(format!("pca_mst/{backend:?}"), |b| {
            b.iter(|| {
                black_box(
                    compute_normals(&mut whole, &mst, RunOptions::new(2), &NoProgress)
                        .expect("normals"),
                )
            })
        });
        g.bench_function(format!("pca_mst_tiled/{backend:?}"), |b| {
            b.iter(|| {
                black_box(
                    compute_normals(&mut tiled, &mst, RunOptions::new(2), &NoProgress)
                        .expect("normals"),
                )
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
