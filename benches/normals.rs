//! Normals end to end through the pipeline (store already built): PCA only,
//! and PCA + spanning-tree orientation, on a noisy torus, untiled and tiled.

use criterion::{criterion_group, criterion_main, Criterion};
use scanmesh::io::memory::MemoryReader;
use scanmesh::normals::{compute_normals, NormalParams, Orientation};
use scanmesh::pipeline::{NoProgress, RunOptions};
use scanmesh::spatial::KnnBackend;
use scanmesh::store::{build_store, BuildOptions, PointStore, TileTarget};
use scanmesh::synth::{generate, Shape};
use std::hint::black_box;

const N: usize = 1_000_000;

fn store(dir: &std::path::Path, tile_points: u64) -> PointStore {
    let scan = generate(&Shape::torus(1.0, 0.3), N, 0.0002, 1).expect("generate");
    let mut reader = MemoryReader::new("torus", scan.points, None);
    let opts = BuildOptions {
        tiles: TileTarget::Points(tile_points),
        ..BuildOptions::default()
    };
    build_store(&mut reader, dir, &opts, &NoProgress).expect("store")
}

fn bench(c: &mut Criterion) {
    let dir = tempfile::tempdir().expect("tmp");
    let mut whole = store(&dir.path().join("whole"), u64::MAX);
    let mut tiled = store(&dir.path().join("tiled"), 150_000);
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
