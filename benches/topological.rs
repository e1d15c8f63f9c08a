//! Topological neighbours (paper 3) against plain kNN for every point of a
//! 1M-point noisy wavy sheet, k = 15, with rayon. Plain kNN is timed on the
//! R*-tree (best-first, the `KnnIndex` impl, and the paper's hollow sphere)
//! and on kiddo's immutable kd-tree for reference. The target:
//! topological under 4x plain kNN. `TOPO_BENCH_POINTS` overrides the size.

use std::hint::black_box;
use std::num::NonZero;

use criterion::{criterion_group, criterion_main, Criterion};
use glam::DVec3;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;
use scanmesh::spatial::rtree::RTreeIndex;
use scanmesh::spatial::topological::{all_topological, TopoParams};
use scanmesh::spatial::{KnnIndex, Neighbour};

const K: usize = 15;

/// SplitMix64, so the sheet is the same on every run.
fn next(state: &mut u64) -> f64 {
    *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
}

/// A jittered grid of spacing 1 on `z = 3 sin(x/25) cos(y/40)` with noise.
fn wavy_sheet(n: usize) -> Vec<DVec3> {
    let side = (n as f64).sqrt().ceil() as usize;
    let mut state = 2024;
    (0..n)
        .map(|i| {
            let x = (i % side) as f64 + next(&mut state) - 0.5;
            let y = (i / side) as f64 + next(&mut state) - 0.5;
            let z = 3.0 * (x / 25.0).sin() * (y / 40.0).cos() + 0.05 * (next(&mut state) - 0.5);
            DVec3::new(x, y, z)
        })
        .collect()
}

fn all_knn(index: &RTreeIndex, points: &[DVec3], hollow: bool) -> f64 {
    (0..points.len() as u32)
        .into_par_iter()
        .map_init(Vec::<Neighbour>::new, |out, i| {
            let q = points[i as usize];
            if hollow {
                index.knn_hollow(q, K, Some(i), out);
            } else {
                index.knn_best_first(q, K, Some(i), out);
            }
            out.last().map_or(0.0, |n| n.dist2)
        })
        .sum()
}

fn all_kiddo(tree: &ImmutableKdTree<f64, 3>, points: &[DVec3]) -> f64 {
    let n = NonZero::new(K + 1).unwrap_or(NonZero::<usize>::MIN);
    points
        .par_iter()
        .map(|p| {
            let found = tree
                .query(&p.to_array())
                .nearest_n::<SquaredEuclidean<f64>>(n)
                .execute();
            found.last().map_or(0.0, |r| r.distance)
        })
        .sum()
}

fn bench(c: &mut Criterion) {
    let n = std::env::var("TOPO_BENCH_POINTS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1_000_000);
    let points = wavy_sheet(n);
    let tie: Vec<u64> = (0..n as u64).collect();
    let index = RTreeIndex::new(&points, &tie).unwrap();
    let coords: Vec<[f64; 3]> = points.iter().map(|p| p.to_array()).collect();
    let kd = ImmutableKdTree::<f64, 3>::new_from_slice(&coords).unwrap();
    let params = TopoParams {
        k: K,
        ..TopoParams::default()
    };

    let mut group = c.benchmark_group(format!("all_points_k{K}_n{n}"));
    group.sample_size(10);
    group.bench_function("build_rtree", |b| {
        b.iter(|| black_box(RTreeIndex::new(&points, &tie).unwrap().len()))
    });
    group.bench_function("knn_rtree_best_first", |b| {
        b.iter(|| black_box(all_knn(&index, &points, false)))
    });
    group.bench_function("knn_rtree_hollow_sphere_knnindex", |b| {
        b.iter(|| black_box(all_knn(&index, &points, true)))
    });
    group.bench_function("knn_kiddo_immutable", |b| {
        b.iter(|| black_box(all_kiddo(&kd, &points)))
    });
    group.bench_function("topological", |b| {
        b.iter(|| {
            black_box(
                all_topological(&index, &points, &tie, &params)
                    .unwrap()
                    .len(),
            )
        })
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
