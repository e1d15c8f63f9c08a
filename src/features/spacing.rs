//! Paper 5's mean spacing `d` (section 2, last paragraphs): the mean over
//! the points of each point's mean distance to its 5-7 nearest neighbours
//! (we take 6). The paper estimates it on a sample of `m > N / 20` points;
//! we take every point, in one tile pass with a fixed-point sum, so `d`, and
//! the radius `r = 2..4 d` every later stage derives from it, do not depend
//! on the tiling (a sample of tiles would, as the store's spacing estimate
//! does: ARCHITECTURE.md, "order and address").

use super::stats::ExactSum;
use crate::pipeline::{run_tiles, KernelError, PipelineError, Progress, RunOptions, TileKernel};
use crate::spatial::{build_index, KnnBackend};
use crate::store::PointStore;
use crate::tiling::TilePoints;
use rayon::prelude::*;

/// Neighbours whose distances make a point's spacing (paper: 5 to 7).
pub const SPACING_NEIGHBOURS: usize = 6;

struct SpacingKernel {
    margin: f64,
    scale: f64,
}

impl TileKernel for SpacingKernel {
    type Output = ExactSum;

    fn name(&self) -> &'static str {
        "features: spacing"
    }

    fn margin(&self) -> f64 {
        self.margin
    }

    fn run(&self, tile: &TilePoints) -> Result<ExactSum, KernelError> {
        let index =
            build_index(KnnBackend::Grid, &tile.points, &tile.ids).map_err(KernelError::failed)?;
        let k = SPACING_NEIGHBOURS;
        let parts: Vec<(ExactSum, f64)> = (0..tile.n_core)
            .into_par_iter()
            .chunks(4096)
            .map(|chunk| {
                let mut sum = ExactSum::new(self.scale);
                let mut short = 0.0f64;
                let mut nbrs = Vec::new();
                for i in chunk {
                    let p = tile.points[i];
                    index.knn(p, k, Some(i as u32), &mut nbrs);
                    let reach = match nbrs.last() {
                        Some(n) if nbrs.len() >= k => n.dist2.sqrt(),
                        _ => f64::INFINITY,
                    };
                    short = short.max(reach - tile.room(p));
                    let mean =
                        nbrs.iter().map(|n| n.dist2.sqrt()).sum::<f64>() / nbrs.len().max(1) as f64;
                    sum.add(mean);
                }
                (sum, short)
            })
            .collect();
        let mut total = ExactSum::new(self.scale);
        let mut short = 0.0f64;
        for (s, sh) in &parts {
            total.merge(s);
            short = short.max(*sh);
        }
        KernelError::unless_short(short, tile.margin)?;
        Ok(total)
    }
}

/// The mean spacing `d` of every point of `store`, given the store's
/// spacing estimate (for the first margin and the sum's scale only).
pub fn mean_spacing(
    store: &PointStore,
    estimate: f64,
    opts: RunOptions,
    progress: &dyn Progress,
) -> Result<f64, PipelineError> {
    // The scale must not depend on the tiling: the input bounds fix it.
    let extent = store.relative_bounds().extent().max_element();
    let kernel = SpacingKernel {
        margin: 3.0 * estimate * (SPACING_NEIGHBOURS as f64).sqrt(),
        scale: if extent > 0.0 { extent / 4096.0 } else { 1.0 },
    };
    let mut total = ExactSum::new(kernel.scale);
    run_tiles(store, &kernel, opts, progress, |_, s| {
        total.merge(&s);
        Ok(())
    })?;
    Ok(total.mean())
}
