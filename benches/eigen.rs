//! Symmetric 3x3 eigen-solver benchmark: the analytic `sym3_eigen` against
//! the cyclic Jacobi it replaced (`sym3_eigen_jacobi`), on 10k realistic PCA
//! covariances: `s R diag(l) R^T` with a random rotation R, eigenvalues like
//! a noisy planar neighbourhood's (`l0` in [1e-6, 1e-2], `l1` in [0.3, 1],
//! `l2 = 1`) and a scale `s` of spacing^2, 1e-6 .. 1.
//!
//! Run: `cargo bench --bench eigen -- --warm-up-time 1 --measurement-time 5`.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use glam::{DMat3, DQuat, DVec3};
use scanmesh::normals::eigen::{sym3_eigen, sym3_eigen_jacobi};
use scanmesh::synth::Rng;

const N: usize = 10_000;

fn covariances(n: usize, seed: u64) -> Vec<[[f64; 3]; 3]> {
    let mut rng = Rng::new(seed);
    (0..n)
        .map(|_| {
            let mut c = || rng.range(-1.0, 1.0);
            let r = DMat3::from_quat(DQuat::from_xyzw(c(), c(), c(), c()).normalize());
            let l = DVec3::new(10f64.powf(rng.range(-6.0, -2.0)), rng.range(0.3, 1.0), 1.0);
            let m = r * DMat3::from_diagonal(l * 10f64.powf(rng.range(-6.0, 0.0))) * r.transpose();
            std::array::from_fn(|i| m.row(i).to_array())
        })
        .collect()
}

type Solver = fn([[f64; 3]; 3]) -> ([f64; 3], [DVec3; 3]);

fn bench_eigen(c: &mut Criterion) {
    let matrices = covariances(N, 7);
    let mut group = c.benchmark_group("sym3_eigen_10k");
    let solvers: [(&str, Solver); 2] = [("analytic", sym3_eigen), ("jacobi", sym3_eigen_jacobi)];
    for (name, solve) in solvers {
        group.bench_function(name, |b| {
            b.iter(|| {
                let sum = matrices.iter().fold(0.0, |acc, &m| {
                    let (values, vectors) = solve(black_box(m));
                    acc + values[0] + vectors[0].z
                });
                black_box(sum)
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench_eigen);
criterion_main!(benches);
