//! kNN benchmarks: both backends, 1M points on a surface, k = 12 for every
//! point (excluding itself), queries spread over the rayon pool, taken in
//! input order and in the grid's cell order; build time measured separately.
//!
//! Run: `cargo bench --bench knn -- --warm-up-time 1 --measurement-time 5`.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use glam::DVec3;
use rayon::prelude::*;
use scanmesh::spatial::{GridIndex, KdIndex, KnnIndex, Neighbour};
use scanmesh::synth::{fibonacci_direction, Rng};

const N: usize = 1_000_000;
const K: usize = 12;

/// Fibonacci sphere of radius 10 m at a UTM-like offset, 1 mm radial noise.
fn sphere(n: usize) -> Vec<DVec3> {
    let mut rng = Rng::new(1);
    let centre = DVec3::new(5.0e5, 4.2e6, 100.0);
    (0..n)
        .map(|i| centre + (10.0 + rng.range(-1e-3, 1e-3)) * fibonacci_direction(i, n))
        .collect()
}

/// 100 m x 100 m jittered sheet with 2 m waves, scan-line order.
fn wavy_sheet(n: usize) -> Vec<DVec3> {
    let mut rng = Rng::new(2);
    let side = (n as f64).sqrt().ceil() as usize;
    let step = 100.0 / side as f64;
    (0..n)
        .map(|i| {
            let x = (i % side) as f64 * step + rng.range(-0.3 * step, 0.3 * step);
            let y = (i / side) as f64 * step + rng.range(-0.3 * step, 0.3 * step);
            let z = 2.0 * (x * 0.2).sin() * (y * 0.15).cos() + rng.range(-0.01, 0.01);
            DVec3::new(x, y, z)
        })
        .collect()
}

/// kNN of every point (excluding itself), queries taken in `order`.
fn all_knn(index: &dyn KnnIndex, points: &[DVec3], order: &[u32]) -> usize {
    order
        .par_iter()
        .map_init(
            || Vec::<Neighbour>::with_capacity(K + 1),
            |out, &i| {
                index.knn(points[i as usize], K, Some(i), out);
                out.len()
            },
        )
        .sum()
}

fn bench_knn(c: &mut Criterion) {
    let tie: Vec<u64> = (0..N as u64).collect();
    for (surface, points) in [("sphere", sphere(N)), ("sheet", wavy_sheet(N))] {
        let mut group = c.benchmark_group(format!("knn_1M_k12_{surface}"));
        group.sample_size(10);
        group.bench_function("build_grid", |b| {
            b.iter(|| black_box(GridIndex::new(&points, &tie).map(|g| g.len())))
        });
        group.bench_function("build_kdtree", |b| {
            b.iter(|| black_box(KdIndex::new(&points, &tie).map(|g| g.len())))
        });
        let grid = GridIndex::new(&points, &tie).expect("grid");
        let kd = KdIndex::new(&points, &tie).expect("kd-tree");
        let input_order: Vec<u32> = (0..N as u32).collect();
        let cell_order = grid.cell_order().to_vec();
        for (order_name, order) in [("input_order", &input_order), ("cell_order", &cell_order)] {
            group.bench_function(format!("query_all_grid_{order_name}"), |b| {
                b.iter(|| black_box(all_knn(&grid, &points, order)))
            });
            group.bench_function(format!("query_all_kdtree_{order_name}"), |b| {
                b.iter(|| black_box(all_knn(&kd, &points, order)))
            });
        }
        group.finish();
    }
}

criterion_group!(benches, bench_knn);
criterion_main!(benches);
