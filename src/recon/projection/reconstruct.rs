//! `reconstruct --method projection` end to end over a store: the tile
//! kernel (`kernel.rs`) over every tile, vertices and fixed triangles
//! streamed by the stitcher, the seam bands re-grown at the end.
//!
//! Normals are the kernel's own PCA planes, oriented while growing
//! (section 2.6): no normals pass, no Riemannian graph.

use super::kernel::ProjectionKernel;
use super::params::{BadParameter, ProjectionParams};
use super::stitch::{StitchError, StitchReport, Stitcher};
use crate::mesh::{MeshError, MeshFormat, MeshWriter};
use crate::normals::NormalHood;
use crate::pipeline::{run_tiles, PipelineError, Progress, RunOptions, RunStats};
use crate::store::spacing::ensure_spacing;
use crate::store::{PointStore, StoreError};
use std::path::Path;

/// Half-width of the band re-grown along tile faces, in spacings.
pub const BAND_SPACINGS: f64 = 4.0;

#[derive(Clone, Copy, Debug, Default)]
pub struct ProjectionReport {
    /// The store's spacing estimate, which sets the band and the margins
    /// (never a result within a tile).
    pub spacing: f64,
    pub band: f64,
    pub frame: f64,
    /// Points processed by the tiles' growth (margins included).
    pub processed: u64,
    pub stitch: StitchReport,
    pub run: RunStats,
}

#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ProjectionError {
    #[error(transparent)]
    Parameter(#[from] BadParameter),
    #[error(transparent)]
    Pipeline(#[from] PipelineError),
    #[error(transparent)]
    Store(#[from] StoreError),
    #[error(transparent)]
    Mesh(#[from] MeshError),
    #[error(transparent)]
    Stitch(#[from] StitchError),
}

/// The k-th neighbour distance of a uniform planar sample with mean
/// spacing `spacing`: `sqrt(k / (pi rho))` with `rho = 1 / (4 spacing^2)`.
fn kth_distance(spacing: f64, k: usize) -> f64 {
    2.0 * spacing * (k as f64 / std::f64::consts::PI).sqrt()
}

pub fn reconstruct_projection(
    store: &mut PointStore,
    params: &ProjectionParams,
    output: &Path,
    format: MeshFormat,
    opts: RunOptions,
    progress: &dyn Progress,
) -> Result<ProjectionReport, ProjectionError> {
    params.validate()?;
    let spacing = ensure_spacing(store)?;
    let reach = match params.neighbourhood {
        NormalHood::Knn => kth_distance(spacing, params.k),
        NormalHood::Topological { .. } => 2.0 * kth_distance(spacing, params.k),
    };
    let band = BAND_SPACINGS * spacing;
    // A frame point's list must lie in the frame: two reaches leave room
    // for the lists of the points the band's fans reach.
    let frame = 2.0 * reach + 2.0 * spacing;
    let kernel = ProjectionKernel {
        params: *params,
        band,
        frame,
        initial_margin: band + frame + reach,
    };
    let mut stitcher = Stitcher::new(MeshWriter::create(output, format)?)?;
    let mut processed = 0;
    let store = &*store;
    let run = run_tiles(store, &kernel, opts, progress, |t, out| {
        processed += out.processed;
        stitcher
            .add_tile(store, t, &store.tiles()[t], &out)
            .map_err(|e| PipelineError::Seam(e.to_string()))
    })?;
    let stitch = stitcher.finish(params)?;
    Ok(ProjectionReport {
        spacing,
        band,
        frame,
        processed,
        stitch,
        run,
    })
}
