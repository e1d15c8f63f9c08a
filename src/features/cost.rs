//! What `curvature` and `features` runs cost, for the memory plan
//! (`pipeline::plan`): the largest of the passes they chain (normals when
//! the store has none, the curvature kernel, the feature kernel), the
//! normals' orientation state, the input-order export and the lines kept
//! until the seams are joined. Checked on the 10M-point noisy dragon
//! (peak-rss, scratch on disk, 256 tiles): `features --mem 256MiB` peaks
//! at 236 MiB, `--mem 240MiB` (the smallest it takes) at 224 MiB.
//! The join is the run's peak: it starts where the tiles left the heap
//! (their freed memory stays with the allocator's worker arenas, ~55 MiB
//! at 10M), so it must not copy the lines; holding each line twice over
//! took the same run to 277 MiB (2026-11-24).

use super::params::FeatureParams;
use super::CurvatureParams;
use crate::memory::plan::MARGIN_FACTOR;
use crate::pipeline::KernelCost;

/// Peak bytes per loaded point of the curvature kernel: the tile's
/// positions, ids and normals, the radius grid, the hood answers and the
/// per-point results. Measured with `tools/peak_rss.rs`, one tile and one
/// thread on stores with normals: peak RSS 110 MiB on the 437,645-point
/// dragon and 234 MiB on the 1M-point noisy dragon, 231 B per point of the
/// difference (the export's window, holding every record at that budget,
/// included).
pub const CURVATURE_BYTES_PER_POINT: u64 = 250;

/// Peak bytes per loaded point of the feature kernel (curvature reused
/// from the store): the candidate sets, enhanced and smoothed points and
/// their grids. Measured as above: 77.6 MiB and 178 MiB, 187 B per point.
pub const FEATURES_BYTES_PER_POINT: u64 = 210;

/// Loaded points per core point of the feature kernel at the tile sizes a
/// small budget gives (60-80k points): its margin is a growth cell plus
/// the stages' radius chain (~59 d at the defaults), far more than the
/// plan's `MARGIN_FACTOR` allows for. Measured at 10M points in 256 MiB
/// with 78k-point tiles and a 75 d margin: 175 MiB of tiles in flight,
/// 4.0 loaded points per core point.
const FEATURES_LOADED_PER_CORE: f64 = 3.5;

/// Line vertices per input point allowed for: 0.026 on the dragon and
/// 0.041 on the 10M noisy dragon at the default thresholds.
const LINE_VERTICES_PER_POINT: f64 = 0.05;

/// Bytes per line vertex while the seams are joined (all polylines, the
/// copies' grid, the repair's graph and grid): the 10M noisy dragon's
/// 408k vertices took the RSS from 183 to 258 MiB after the tiles, ~190 B
/// each (with the grown copies kept through the repair).
const BYTES_PER_LINE_VERTEX: f64 = 200.0;

/// Scratch bytes per point beside the store of the passes after the
/// normals': the curvature columns (4 per value, and the flags). Measured
/// peaks beside the store: curvature 94 B, features 74 B on the 1M dragon;
/// 69 B each on a 110k LAS.
const CURVATURE_COLUMNS: u64 = 4 * super::curvature::VALUES as u64 + 1;

impl CurvatureParams {
    /// Scratch beside the store until the export: the normals' and the
    /// curvature columns (`features` exports nothing per point).
    fn scratch_before_export(&self) -> u64 {
        self.normals.cost().scratch_per_point + CURVATURE_COLUMNS
    }

    /// A `curvature` run: normals when needed, the kernel, the store's
    /// point export in input order (its windows, which it shrinks for the
    /// values they carry, and its reorder file of slot, values and flags
    /// on disk).
    pub fn cost(&self) -> KernelCost {
        let normals = self.normals.cost();
        let values = 4 * super::curvature::VALUES as u64 + 1;
        KernelCost {
            bytes_per_point: normals.bytes_per_point.max(CURVATURE_BYTES_PER_POINT),
            window_bytes_per_point: crate::normals::EXPORT_BYTES_PER_POINT,
            scratch_per_point: self.scratch_before_export() + 4 + values,
            export_scratch_per_point: self.scratch_before_export() + 4 + values,
            // A PLY record: x y z double, then the values and flags (a
            // LAS input's records, kept, are longer by their own length).
            output_per_point: 24 + values,
            parallel_in_tile: false,
            margin_spacings: 0.0,
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
        // The plan allows for MARGIN_FACTOR loaded points per core point.
        let features = FEATURES_BYTES_PER_POINT as f64 * FEATURES_LOADED_PER_CORE / MARGIN_FACTOR;
        KernelCost {
            bytes_per_point: curvature.bytes_per_point.max(features.ceil() as u64),
            resident_per_point: line_bytes,
            window_bytes_per_point: 0,
            scratch_per_point: self.curvature.scratch_before_export(),
            export_scratch_per_point: self.curvature.scratch_before_export(),
            // Vertices (24 B) and edges (9 B) of the PLY.
            output_per_point: (LINE_VERTICES_PER_POINT * 33.0).ceil() as u64,
            parallel_in_tile: false,
            margin_spacings: 0.0,
            ..curvature
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::memory::plan::{MemoryPlan, MIN_TILE_POINTS};
    use crate::pipeline::MemoryBudget;

    #[test]
    fn ten_million_points_plan_within_256_mib_on_two_threads() {
        let budget = MemoryBudget::new(256 << 20, 2);
        let features = FeatureParams::default().cost();
        let curvature = CurvatureParams::default().cost();
        for cost in [features, curvature] {
            let plan = MemoryPlan::new(budget, 10_000_000, &cost).unwrap();
            assert!(plan.tile_points >= MIN_TILE_POINTS, "{plan:?}");
            // Never below what the normals pass before it needs.
            let normals = CurvatureParams::default().normals.cost();
            assert!(cost.bytes_per_point >= normals.bytes_per_point);
            assert!(cost.bytes_per_point >= CURVATURE_BYTES_PER_POINT);
        }
        assert!(features.bytes_per_point >= FEATURES_BYTES_PER_POINT);
        assert!(features.resident_per_point > 0.0 && curvature.window_bytes_per_point > 0);
    }
}
