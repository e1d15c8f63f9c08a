//! The room for tiles is asked for before a tile is loaded: a tile whose
//! margin grew past the room is refused without holding its points, and a
//! tile that needs more once seen waits holding nothing.

use super::{run_tiles, KernelError, PipelineError, RunOptions, TileKernel};
use crate::progress::NoProgress;
use crate::store::PointStore;
use crate::tiling::TilePoints;
use glam::DVec3;
use std::sync::atomic::{AtomicU64, Ordering};

const BYTES_PER_POINT: u64 = 1000;

/// Asks for margin until a tile holds `wanted` points; records the largest
/// tile loaded (the pipeline asks `bytes_for` of every tile it loads).
struct Greedy {
    wanted: usize,
    largest: AtomicU64,
}

impl TileKernel for Greedy {
    type Output = usize;
    fn name(&self) -> &'static str {
        "greedy"
    }
    fn margin(&self) -> f64 {
        0.0
    }
    fn bytes_per_loaded_point(&self) -> Option<u64> {
        Some(BYTES_PER_POINT)
    }
    fn bytes_for(&self, tile: &TilePoints) -> Option<u64> {
        let n = tile.points.len() as u64;
        self.largest.fetch_max(n, Ordering::SeqCst);
        Some(n * BYTES_PER_POINT)
    }
    fn run(&self, tile: &TilePoints) -> Result<usize, KernelError> {
        if tile.points.len() < self.wanted {
            return Err(KernelError::MarginTooSmall {
                needed: tile.margin + 1.0,
            });
        }
        Ok(tile.n_core)
    }
}

fn line_store(dir: &std::path::Path) -> PointStore {
    let pts: Vec<DVec3> = (0..4000)
        .map(|i| DVec3::new(i as f64 * 0.01, (i % 7) as f64 * 0.01, 0.0))
        .collect();
    crate::store::test_store::store_of(pts, 500, dir)
}

fn options(room_points: u64) -> RunOptions {
    RunOptions {
        tile_bytes: Some(600 * BYTES_PER_POINT),
        tile_room: Some(room_points * BYTES_PER_POINT),
        ..RunOptions::new(2)
    }
}

#[test]
fn a_tile_past_the_room_is_refused_before_it_is_loaded() {
    let dir = tempfile::tempdir().unwrap();
    let store = line_store(&dir.path().join("s"));
    let kernel = Greedy {
        wanted: 3000,
        largest: AtomicU64::new(0),
    };
    let err = run_tiles(&store, &kernel, options(1500), &NoProgress, |_, _| Ok(()))
        .expect_err("3000 points do not fit a room of 1500");
    let PipelineError::OverBudget { points, .. } = err else {
        panic!("{err}")
    };
    assert!(points > 1500, "{points}");
    let largest = kernel.largest.load(Ordering::SeqCst);
    assert!(largest <= 1500, "a tile of {largest} points was loaded");
}

#[test]
fn tiles_within_the_room_run_whatever_their_margins() {
    let dir = tempfile::tempdir().unwrap();
    let store = line_store(&dir.path().join("s"));
    let kernel = Greedy {
        wanted: 1200,
        largest: AtomicU64::new(0),
    };
    let mut cores = 0;
    run_tiles(&store, &kernel, options(2000), &NoProgress, |_, n| {
        cores += n;
        Ok(())
    })
    .expect("every tile fits");
    assert_eq!(cores, 4000);
}
