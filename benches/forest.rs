//! Tile minimum-spanning-forest benchmark: the Riemannian graph of a 500k
//! point noisy torus built the way the normals kernel builds it (k = 12
//! nearest from the grid index, PCA normals, the TangentOffset cost, a
//! mutual pair once), then `spanning_forest` on a fresh copy of the edges.
//! The points are put in Morton order first, as the store orders a tile's
//! points (ids and local numbers are then spatially coherent).
//! `sort_then_kruskal` is the algorithm before filter-Kruskal (parallel sort
//! of every edge, dedup, Kruskal with the parity union-find), measured in the
//! same run for comparison on this shared, noisy machine.
//!
//! Run: `cargo bench --bench forest -- --warm-up-time 1 --measurement-time 5`.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, BatchSize, Criterion};
use glam::DVec3;
use rayon::prelude::*;
use scanmesh::normals::forest::{reference_forest, spanning_forest, Edge};
use scanmesh::normals::pca::fit_plane;
use scanmesh::spatial::{GridIndex, KnnIndex, Neighbour};
use scanmesh::synth::{generate, Shape};

const N: usize = 500_000;
const K: usize = 12;

/// 63-bit Morton key of `p` quantised to 21 bits per axis within `[lo, hi]`.
fn morton(p: DVec3, lo: DVec3, hi: DVec3) -> u64 {
    let q = (p - lo) / (hi - lo).max(DVec3::splat(1e-300)) * ((1u64 << 21) - 1) as f64;
    let spread = |v: f64| {
        let v = v.clamp(0.0, ((1u64 << 21) - 1) as f64) as u64;
        (0..21).fold(0u64, |acc, bit| acc | ((v >> bit) & 1) << (3 * bit))
    };
    spread(q.x) | spread(q.y) << 1 | spread(q.z) << 2
}

fn morton_ordered(mut points: Vec<DVec3>) -> Vec<DVec3> {
    let lo = points.iter().fold(DVec3::MAX, |a, &p| a.min(p));
    let hi = points.iter().fold(DVec3::MIN, |a, &p| a.max(p));
    points.sort_by_cached_key(|&p| morton(p, lo, hi));
    points
}

fn neighbourhoods(points: &[DVec3]) -> Vec<Vec<Neighbour>> {
    let tie: Vec<u64> = (0..points.len() as u64).collect();
    let grid = GridIndex::new(points, &tie).expect("grid");
    (0..points.len())
        .into_par_iter()
        .map_init(Vec::new, |out, i| {
            grid.knn(points[i], K, Some(i as u32), out);
            out.clone()
        })
        .collect()
}

/// The kernel's TangentOffset cost: `1 - |n_i . n_j|` plus the mean offset
/// of the pair from the two tangent planes over its length.
fn cost(d: DVec3, ni: DVec3, nj: DVec3, dot: f64) -> f64 {
    let len = d.length();
    let offset = if len > 0.0 {
        (d.dot(ni).abs() + d.dot(nj).abs()) / (2.0 * len)
    } else {
        0.0
    };
    1.0 - dot.abs() + offset
}

fn riemannian_graph(points: &[DVec3]) -> Vec<Edge> {
    let hoods = neighbourhoods(points);
    let normals: Vec<Option<DVec3>> = hoods
        .par_iter()
        .enumerate()
        .map(|(i, h)| fit_plane(points, i, h).ok().map(|f| f.normal))
        .collect();
    let mut edges = Vec::with_capacity(points.len() * 8);
    for (i, h) in hoods.iter().enumerate() {
        let Some(ni) = normals[i] else { continue };
        for nb in h {
            let j = nb.index as usize;
            let mutual = hoods[j].iter().any(|m| m.index as usize == i);
            if mutual && j < i {
                continue;
            }
            if let Some(nj) = normals[j] {
                let dot = ni.dot(nj);
                let c = cost(points[j] - points[i], ni, nj, dot);
                edges.push(Edge::with_cost(i as u32, j as u32, c, dot));
            }
        }
    }
    edges
}

fn bench_forest(c: &mut Criterion) {
    let scan = generate(&Shape::torus(1.0, 0.3), N, 0.0002, 1).expect("generate");
    let edges = riemannian_graph(&morton_ordered(scan.points));
    eprintln!("{} points, {} edges", N, edges.len());
    assert_eq!(
        spanning_forest(edges.clone(), N),
        reference_forest(edges.clone(), N)
    );
    let mut group = c.benchmark_group("forest_500k_k12");
    group.sample_size(10);
    group.bench_function("spanning_forest", |b| {
        b.iter_batched(
            || edges.clone(),
            |e| black_box(spanning_forest(e, N)),
            BatchSize::LargeInput,
        )
    });
    group.bench_function("sort_then_kruskal", |b| {
        b.iter_batched(
            || edges.clone(),
            |e| black_box(reference_forest(e, N)),
            BatchSize::LargeInput,
        )
    });
    group.finish();
}

criterion_group!(benches, bench_forest);
criterion_main!(benches);
