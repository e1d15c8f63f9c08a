//! Mesh evaluation at scale: `quality` and `compare` on a procedural torus
//! of exactly 1,000,000 triangles (1000 x 500 quads), compared against a
//! coarser, slightly fatter torus. Run with
//! `cargo bench --bench mesh_eval -- --verbose` to see the medians.

use criterion::{criterion_group, criterion_main, Criterion, SamplingMode};
use scanmesh::mesh::{compare, quality, shapes, Reference};
use std::hint::black_box;
use std::time::Duration;

fn mesh_eval(c: &mut Criterion) {
    let mesh = shapes::torus(2.0, 0.5, 1000, 500);
    let reference = shapes::torus(2.0, 0.505, 700, 350);
    assert_eq!(mesh.triangles.len(), 1_000_000);
    let mut group = c.benchmark_group("mesh_eval_1M");
    group
        .sample_size(10)
        .sampling_mode(SamplingMode::Flat)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(20));
    group.bench_function("quality", |b| {
        b.iter(|| black_box(quality(black_box(&mesh))))
    });
    group.bench_function("compare_mesh", |b| {
        b.iter(|| black_box(compare(black_box(&mesh), Reference::Mesh(&reference))))
    });
    group.finish();
}

criterion_group!(benches, mesh_eval);
criterion_main!(benches);
