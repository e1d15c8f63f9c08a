//! The store's spacing estimate: mean nearest-neighbour distance over a
//! sample of points spread across tiles (exact duplicates left out, since a
//! zero distance says nothing about sampling density).
//!
//! The nearest neighbour of a sampled point is found by brute force over the
//! tile's runs of consecutive (Morton-ordered) points (`spatial::blocks`):
//! the exact nearest distance within the tile, the same value a kNN index
//! gives; sampled tiles run in parallel.

use super::{PointStore, StoreError, TileEntry};
use crate::spatial::blocks::Blocks;
use rayon::prelude::*;

/// Tiles sampled and points sampled per tile.
const SAMPLE_TILES: usize = 16;
const SAMPLE_POINTS: usize = 1024;

/// The spacing from the manifest, estimating and saving it first if absent.
pub fn ensure_spacing(store: &mut PointStore) -> Result<f64, StoreError> {
    if let Some(s) = store.manifest.spacing {
        return Ok(s);
    }
    let s = estimate_spacing(store)?;
    store.manifest.spacing = Some(s);
    store.save_manifest()?;
    Ok(s)
}

/// Mean nearest-neighbour distance over a sample; falls back to a
/// bounding-box estimate when every sampled point is a duplicate.
pub(crate) fn estimate_spacing(store: &PointStore) -> Result<f64, StoreError> {
    let tiles: Vec<_> = store.tiles().iter().filter(|t| t.count > 1).collect();
    let step = tiles.len().div_ceil(SAMPLE_TILES).max(1);
    let sampled: Vec<&TileEntry> = tiles.iter().step_by(step).copied().collect();
    let nearest: Vec<Vec<f64>> = sampled
        .par_iter()
        .map(|t| sample_distances(store, t))
        .collect::<Result<_, _>>()?;
    // Summed in sample order, so the estimate does not depend on threads.
    let (mut sum, mut n) = (0.0, 0u64);
    for d in nearest.iter().flatten() {
        sum += d;
        n += 1;
    }
    if n > 0 {
        return Ok(sum / n as f64);
    }
    let extent = store.relative_bounds().extent().max_element();
    Ok(if extent > 0.0 {
        extent / (store.len() as f64).sqrt()
    } else {
        1.0
    })
}

/// Nearest-neighbour distances of a tile's sampled points, in sample order,
/// leaving out points with an exact duplicate.
fn sample_distances(store: &PointStore, t: &TileEntry) -> Result<Vec<f64>, StoreError> {
    let mut pts = Vec::new();
    store.read_points(t.start, t.count, &mut pts)?;
    let stride = (pts.len() / SAMPLE_POINTS).max(1);
    let blocks = Blocks::new(&pts);
    Ok((0..pts.len())
        .step_by(stride)
        .filter_map(|i| blocks.nearest_dist2(&pts, i))
        .filter(|&d2| d2 > 0.0)
        .map(f64::sqrt)
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spatial::blocks::tests::cloud;
    use crate::spatial::brute_knn;

    #[test]
    fn store_estimate_is_the_mean_nearest_distance() {
        for seed in [3u64, 11] {
            let pts = cloud(seed, 20_000);
            let dir = tempfile::tempdir().unwrap();
            let store = crate::store::test_store::store_of(pts, 6000, &dir.path().join("s"));
            // Oracle: the same sample, nearest distances by brute force.
            let (mut sum, mut n) = (0.0, 0u64);
            let (mut p, mut ids) = (Vec::new(), Vec::new());
            let tiles: Vec<_> = store.tiles().iter().filter(|t| t.count > 1).collect();
            let step = tiles.len().div_ceil(SAMPLE_TILES).max(1);
            for t in tiles.iter().step_by(step) {
                store.read_points(t.start, t.count, &mut p).unwrap();
                store.read_indices(t.start, t.count, &mut ids).unwrap();
                for i in (0..p.len()).step_by((p.len() / SAMPLE_POINTS).max(1)) {
                    let nbrs = brute_knn(&p, &ids, p[i], 1, Some(i as u32));
                    if let Some(nb) = nbrs.first().filter(|nb| nb.dist2 > 0.0) {
                        sum += nb.dist2.sqrt();
                        n += 1;
                    }
                }
            }
            assert!(tiles.len() > 2, "seed {seed}: {} tiles", tiles.len());
            let got = estimate_spacing(&store).unwrap();
            assert_eq!(got.to_bits(), (sum / n as f64).to_bits(), "seed {seed}");
        }
    }
}
