//! The inputs the pipeline benches share: a store of a noisy 1M-point torus.

use scanmesh::io::memory::MemoryReader;
use scanmesh::pipeline::NoProgress;
use scanmesh::store::{build_store, BuildOptions, PointStore, TileTarget};
use scanmesh::synth::{generate, Shape};
use std::path::Path;

pub const N: usize = 1_000_000;

/// A store at `dir` of [`N`] torus points (seed 1, noise 0.0002), tiles of
/// at most `tile_points` points.
pub fn torus_store(dir: &Path, tile_points: u64) -> PointStore {
    let scan = generate(&Shape::torus(1.0, 0.3), N, 0.0002, 1).expect("generate");
    let mut reader = MemoryReader::new("torus", scan.points, None);
    let opts = BuildOptions {
        tiles: TileTarget::Points(tile_points),
        ..BuildOptions::default()
    };
    build_store(&mut reader, dir, &opts, &NoProgress).expect("store")
}
