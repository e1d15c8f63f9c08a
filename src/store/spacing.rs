//! The store's spacing estimate: mean nearest-neighbour distance over a
//! sample of points spread across tiles (exact duplicates left out, since a
//! zero distance says nothing about sampling density).

use super::{PointStore, StoreError};
use crate::spatial::{build_index, KnnBackend};

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
pub fn estimate_spacing(store: &PointStore) -> Result<f64, StoreError> {
    let tiles: Vec<_> = store.tiles().iter().filter(|t| t.count > 1).collect();
    let step = tiles.len().div_ceil(SAMPLE_TILES).max(1);
    let (mut pts, mut ids) = (Vec::new(), Vec::new());
    let (mut sum, mut n) = (0.0, 0u64);
    let mut nbrs = Vec::new();
    for t in tiles.iter().step_by(step) {
        store.read_points(t.start, t.count, &mut pts)?;
        store.read_indices(t.start, t.count, &mut ids)?;
        let index = build_index(KnnBackend::KdTree, &pts, &ids)?;
        let stride = (pts.len() / SAMPLE_POINTS).max(1);
        for i in (0..pts.len()).step_by(stride) {
            index.knn(pts[i], 1, Some(i as u32), &mut nbrs);
            if let Some(nb) = nbrs.first().filter(|nb| nb.dist2 > 0.0) {
                sum += nb.dist2.sqrt();
                n += 1;
            }
        }
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
