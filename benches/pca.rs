//! PCA plane-fit benchmark: 1M precomputed k = 12 neighbourhoods on a noisy
//! sphere at a UTM-like offset, fitted in parallel over the rayon pool.
//!
//! Run: `cargo bench --bench pca -- --warm-up-time 1 --measurement-time 5`.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use glam::DVec3;
use rayon::prelude::*;
use scanmesh::normals::pca::fit_plane;
use scanmesh::spatial::{GridIndex, KnnIndex, Neighbour};
use scanmesh::synth::fibonacci_direction;

const N: usize = 1_000_000;
const K: usize = 12;

/// Fibonacci sphere of radius 10 m, radial noise from a hash of the index.
fn sphere(n: usize) -> Vec<DVec3> {
    let centre = DVec3::new(5.0e5, 4.2e6, 100.0);
    (0..n)
        .map(|i| {
            let h = (i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 11;
            let radius = 10.0 + 1e-3 * (h as f64 / (1u64 << 53) as f64 - 0.5);
            centre + radius * fibonacci_direction(i, n)
        })
        .collect()
}

fn neighbourhoods(points: &[DVec3], tie: &[u64]) -> Vec<Neighbour> {
    let grid = GridIndex::new(points, tie).expect("grid");
    let mut nbrs = vec![
        Neighbour {
            dist2: 0.0,
            index: 0
        };
        points.len() * K
    ];
    nbrs.par_chunks_mut(K)
        .enumerate()
        .for_each_init(Vec::new, |out, (i, slot)| {
            grid.knn(points[i], K, Some(i as u32), out);
            slot.copy_from_slice(out);
        });
    nbrs
}

fn bench_pca(c: &mut Criterion) {
    let points = sphere(N);
    let tie: Vec<u64> = (0..N as u64).collect();
    let nbrs = neighbourhoods(&points, &tie);
    let mut group = c.benchmark_group("pca_1M_k12");
    group.sample_size(10);
    group.bench_function("fit_plane_all", |b| {
        b.iter(|| {
            let fitted: usize = nbrs
                .par_chunks(K)
                .enumerate()
                .map(|(i, nb)| fit_plane(&points, i, nb).is_ok() as usize)
                .sum();
            black_box(fitted)
        })
    });
    group.finish();
}

criterion_group!(benches, bench_pca);
criterion_main!(benches);
