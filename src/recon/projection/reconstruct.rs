//! `reconstruct --method projection` end to end over a store: the tile
//! kernel (`kernel.rs`) runs the lattice jobs (`lattice.rs`) each tile
//! owns, the stitcher streams vertices and triangles and settles the
//! orientation at the end.
//!
//! Normals are the kernel's own PCA planes, oriented while growing
//! (section 2.6): no normals pass, no Riemannian graph.

use super::kernel::ProjectionKernel;
use super::lattice::Lattice;
use super::params::{BadParameter, ProjectionParams};
use super::stitch::{StitchError, StitchReport, Stitcher};
use crate::mesh::{MeshAudit, MeshError, MeshFormat, MeshWriter, Promise};
use crate::normals::NormalHood;
use crate::pipeline::{run_tiles, PipelineError, Progress, RunOptions, RunStats};
use crate::store::spacing::ensure_spacing;
use crate::store::{PointStore, StoreError};
use std::path::Path;

/// The lattice in lattice units (`lattice_unit`): the band every job of
/// a higher level re-grows along the planes; the overlap of each level
/// with the lower ones (a hole up to this size where a lower level
/// stopped can still be closed: at 4 units the 1M dragon kept 681 loops,
/// at 8, 56; since three-edge holes are closed after each job, 9 units
/// keep 50 loops and 8, at the floor spill + view + unit sets, 52, in 2 %
/// less CPU); the spill; and the cell, more than twice the corners'
/// half-width `BAND + 3 OVERLAP`. The cell sets how often a point is read:
/// a job reads its window's box grown by spill and view, and the higher
/// levels' boxes span nearly a cell, so at 64 units the 1M dragon's jobs
/// read 6.0M points for 1M; at 96 units the run took a fifth less CPU
/// (the same 0 non-manifold, inconsistent and self-intersecting, 57
/// loops against 51, the same distances and slivers), and the 10M dragon
/// at `--mem 512MiB` peaked at 357 MiB (64 tiles, 1.25 runs per job);
/// 128 units saved little more and peaked at 455 MiB (the margin grows
/// with the cell).
pub const BAND_UNITS: f64 = 4.0;
pub const OVERLAP_UNITS: f64 = 8.0;
pub const CELL_UNITS: f64 = 96.0;
/// How far a job grows beyond its window (triangles it drops): where the
/// window's fronts meet, so that they meet outside it. The 1M dragon at
/// 3 / 2 / 1.5 / 1 / 0.5 units: 6.55 / 5.95 / 5.86 / 5.80 / 5.59 s of
/// CPU, 57 / 58 / 61 / 60 / 63 loops, 0.965 / 0.971 / 0.979 / 1.019 /
/// 1.225 % of triangles under 10 degrees, the same distances (a quarter
/// of the triangles a job made at 3 units were dropped).
pub const SPILL_UNITS: f64 = 2.0;

/// The lattice for a unit and a neighbour list's reach (both absolute).
/// A job reads its points' lists and the triangles at their neighbours,
/// so it sees a reach (and a unit) beyond its spill. The overlap is kept
/// above spill plus view: then a job reads no lower job beyond the lattice
/// plane its window stops short of, and a tile's jobs reach a cell beyond
/// its core, not two (`kernel.rs`).
pub fn lattice(unit: f64, reach: f64) -> Lattice {
    let spill = SPILL_UNITS * unit;
    let view = reach + unit;
    let overlap = (OVERLAP_UNITS * unit).max(spill + view + unit);
    let band = BAND_UNITS * unit;
    Lattice {
        cell: (CELL_UNITS * unit).max(2.0 * (band + 3.0 * overlap) + 2.0 * unit),
        band,
        overlap,
        spill,
        view,
    }
}

/// What the local-projection reconstruction did.
#[derive(Clone, Copy, Debug, Default)]
pub struct ProjectionReport {
    /// The store's spacing estimate, which sets the band and the margins
    /// (never a result within a tile).
    pub spacing: f64,
    /// The job lattice the tiles were cut into.
    pub lattice: Lattice,
    /// Points processed by the tiles' growth (margins included).
    pub processed: u64,
    /// Lattice jobs with points (each owned by one tile), and jobs run in
    /// all (a tile also runs the lower jobs its own read).
    pub jobs: u64,
    /// Lattice jobs run in all, repeats included.
    pub jobs_run: u64,
    /// What joining the jobs' triangles did.
    pub stitch: StitchReport,
    /// The mesh written: its edges, vertices, components and volumes.
    pub audit: MeshAudit,
    /// Tiles, retries and margins of the run.
    pub run: RunStats,
}

/// Errors of the local-projection reconstruction.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ProjectionError {
    /// A parameter is out of range.
    #[error(transparent)]
    Parameter(#[from] BadParameter),
    /// The tile pipeline failed.
    #[error(transparent)]
    Pipeline(#[from] PipelineError),
    /// Reading the store failed.
    #[error(transparent)]
    Store(#[from] StoreError),
    /// Writing the mesh failed.
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// Joining the jobs' triangles failed.
    #[error(transparent)]
    Stitch(#[from] StitchError),
}

impl ProjectionError {
    /// The mesh layer's error inside, when writing the mesh is what failed
    /// (a broken promise carries the audit and names the incomplete file).
    pub fn mesh(&self) -> Option<&MeshError> {
        match self {
            ProjectionError::Mesh(e) | ProjectionError::Stitch(StitchError::Mesh(e)) => Some(e),
            _ => None,
        }
    }
}

/// The k-th neighbour distance of a uniform planar sample with mean
/// spacing `spacing`: `sqrt(k / (pi rho))` with `rho = 1 / (4 spacing^2)`.
fn kth_distance(spacing: f64, k: usize) -> f64 {
    2.0 * spacing * (k as f64 / std::f64::consts::PI).sqrt()
}

/// Reconstructs a mesh from the points of `store` by local projection (paper 2), tile by tile, writing it to `output` in `format`; tiled output equals untiled.
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
    let hood_factor = match params.neighbourhood {
        NormalHood::Knn => 1.0,
        NormalHood::Topological { .. } => 2.0,
    };
    let reach = hood_factor * kth_distance(spacing, params.k);
    let unit = lattice_unit(store, spacing);
    let lattice = lattice(unit, hood_factor * kth_distance(unit, params.k));
    // The farthest job a tile runs reads a cell less the band beyond its
    // core, plus its spill and view, plus the lists of the points there
    // (twice the typical reach: sparser points have longer lists, and a
    // reload costs a whole tile).
    let margin = lattice.cell - lattice.band + lattice.spill + lattice.view + 2.0 * reach;
    let kernel = ProjectionKernel {
        params: *params,
        lattice,
        initial_margin: margin * 1.05,
        slack: store.rounding_reach(),
    };
    // Every directed edge is used once (ARCHITECTURE.md): no non-manifold
    // or inconsistently wound edge, or the mesh is written as incomplete
    // and the run fails.
    let out = MeshWriter::create(output, format)?.promising(Promise::DIRECTED_EDGES);
    let mut stitcher = Stitcher::new(out)?;
    let (mut processed, mut jobs, mut jobs_run) = (0, 0, 0);
    let store = &*store;
    let run = run_tiles(store, &kernel, opts, progress, |t, out| {
        processed += out.processed;
        jobs += out.jobs_owned;
        jobs_run += out.jobs_run;
        stitcher
            .add_tile(store, t, &store.tiles()[t], &out)
            .map_err(PipelineError::seam)
    })?;
    let (stitch, audit) = stitcher.finish()?;
    Ok(ProjectionReport {
        spacing,
        lattice,
        processed,
        jobs,
        jobs_run,
        stitch,
        audit,
        run,
    })
}

/// The lattice's unit length: it sets results (where jobs start and stop),
/// so it must not depend on the tiling, and the store's spacing estimate
/// samples tiles. The unit is therefore computed from what every tiling
/// agrees on, the point count and the bounds: `0.8 * extent / sqrt(n)`
/// (the largest extent; 0.8 makes it about the mean spacing of a scanned
/// object, 1.2 spacings on the 1M dragon ... see ARCHITECTURE.md). An
/// outlier far off would blow that up (a cell holding the whole cloud, a
/// margin to match), so it is kept within a factor 2 of the estimate;
/// only then does the tiling enter.
pub fn lattice_unit(store: &PointStore, spacing: f64) -> f64 {
    let m = &store.manifest();
    let extent = (0..3)
        .map(|a| m.bounds_max[a] - m.bounds_min[a])
        .fold(0.0f64, f64::max);
    let n = (m.count.max(1)) as f64;
    let unit = 0.8 * extent / n.sqrt();
    if !(unit.is_finite() && unit > 0.0) {
        return spacing;
    }
    unit.clamp(0.5 * spacing, 2.0 * spacing)
}
