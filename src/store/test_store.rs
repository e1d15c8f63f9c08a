//! A store of given points in a directory, tiled by at most a number of
//! points: what the unit tests of the layers above the store build on.

use super::{build_store, BuildOptions, PointStore, TileTarget};
use crate::io::memory::MemoryReader;
use crate::progress::NoProgress;
use glam::DVec3;
use std::path::Path;

/// The store of `points` at `dir`, in tiles of at most `tile_points`.
pub(crate) fn store_of(points: Vec<DVec3>, tile_points: u64, dir: &Path) -> PointStore {
    let mut reader = MemoryReader::new("test", points, None);
    let opts = BuildOptions {
        tiles: TileTarget::Points(tile_points),
        ..Default::default()
    };
    match build_store(&mut reader, dir, &opts, &NoProgress) {
        Ok(store) => store,
        Err(e) => panic!("test store at {}: {e}", dir.display()),
    }
}
