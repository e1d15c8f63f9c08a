//! What `curvature` and `features` runs cost, for the memory plan
//! (`pipeline::plan`): the largest of the passes they chain (normals when
//! the store has none, the curvature kernel, the feature kernel), the
//! normals' orientation state, the input-order export and the lines kept
//! until the seams are joined.

use super::export::RECORD;
use super::params::FeatureParams;
use super::CurvatureParams;
use crate::pipeline::KernelCost;

/// Peak bytes per loaded point of the curvature kernel: the tile's
/// positions, ids and normals, the radius grid, the hood answers and the
/// per-point results. Measured with `tools/peak_rss.rs` (one tile, one
/// thread: RSS growth from the 437,645-point dragon to a 1M-point noisy
/// dragon, over the point difference); see ARCHITECTURE.md.
pub const CURVATURE_BYTES_PER_POINT: u64 = 300;

/// Peak bytes per loaded point of the feature kernel: the curvature
/// kernel's inputs plus the candidate sets, enhanced points, smoothed
/// points and their grids, measured as above.
pub const FEATURES_BYTES_PER_POINT: u64 = 400;

/// Line vertices per input point allowed for: 0.026 on the dragon at the
/// default thresholds; twice that for rougher scans.
const LINE_VERTICES_PER_POINT: f64 = 0.05;

/// Bytes per line vertex held until the seams are joined: the position, an
/// edge, its owner and the endpoint grid's entry.
const BYTES_PER_LINE_VERTEX: f64 = 64.0;

/// Scratch bytes per point of the passes before the export: the store
/// (20), normals and flags (13), the orientation's forest runs (24) and
/// labels (8), the curvature columns (4 per value, and the flags).
const SCRATCH_PER_POINT: u64 = 65 + 4 * super::curvature::VALUES as u64 + 1;

impl CurvatureParams {
    /// A `curvature` run: normals when needed, the kernel, the export in
    /// input order (a bucket and a write buffer of slot records per window
    /// point, and the reorder file on disk).
    pub fn cost(&self) -> KernelCost {
        let normals = self.normals.cost();
        let slot = RECORD as u64 + 4;
        KernelCost {
            bytes_per_point: normals.bytes_per_point.max(CURVATURE_BYTES_PER_POINT),
            window_bytes_per_point: 2 * slot,
            scratch_per_point: SCRATCH_PER_POINT + slot,
            output_per_point: RECORD as u64,
            ..normals
        }
    }
}

impl FeatureParams {
    /// A `features` run: the curvature run's passes (no export), the
    /// feature kernel, and the lines kept in memory until the seams join.
    pub fn cost(&self) -> KernelCost {
        let curvature = self.curvature.cost();
        let line_bytes = LINE_VERTICES_PER_POINT * BYTES_PER_LINE_VERTEX;
        KernelCost {
            bytes_per_point: curvature.bytes_per_point.max(FEATURES_BYTES_PER_POINT),
            resident_per_point: line_bytes,
            window_bytes_per_point: 0,
            scratch_per_point: SCRATCH_PER_POINT,
            // Vertices (24 B) and edges (9 B) of the PLY.
            output_per_point: (LINE_VERTICES_PER_POINT * 33.0).ceil() as u64,
            ..curvature
        }
    }
}
