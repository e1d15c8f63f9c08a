//! The disk a run needs at its peak, from the same declared costs as the
//! memory plan: the store built from the input, the stages' scratch beside
//! it (columns, checkpointed tiles, spills) and the output. `info --plan`
//! prints it; a run compares it with the free space before it starts.

use super::plan::KernelCost;

/// Bytes on disk at a run's peak. A run has two: its stages (the store and
/// their scratch) and its export (the store, what the export still reads
/// beside it, and the output growing); on one volume the larger counts,
/// not their sum.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DiskPlan {
    /// The point store (0 when the input already is one).
    pub store: u64,
    /// The stages' scratch beside the store, at their peak.
    pub scratch: u64,
    /// The scratch still beside the store while the output is written.
    pub export_scratch: u64,
    /// The output file.
    pub output: u64,
    /// Unnamed scratch beside the output while it is written.
    pub beside_output: u64,
    /// Of the store, what the export frees before the output grows (its
    /// tile-ordered positions, [`KernelCost::export_frees_positions`]).
    pub freed_at_export: u64,
}

/// Bytes per point of the store's tile-ordered positions (`xyz.f32`).
const POSITION_BYTES: u64 = 12;

impl DiskPlan {
    /// The plan for `points` points whose store takes `store_per_point`
    /// bytes each, under a kernel costing `cost`.
    pub fn new(points: u64, store_per_point: u64, cost: &KernelCost) -> Self {
        DiskPlan {
            store: points.saturating_mul(store_per_point),
            scratch: points.saturating_mul(cost.scratch_per_point),
            export_scratch: points.saturating_mul(cost.export_scratch_per_point),
            output: points.saturating_mul(cost.output_per_point),
            beside_output: points.saturating_mul(cost.beside_output_per_point),
            freed_at_export: match cost.export_frees_positions {
                true => points.saturating_mul(POSITION_BYTES),
                false => 0,
            },
        }
    }

    /// What the scratch directory holds at the peak: the store and the
    /// stages' scratch.
    pub fn scratch_dir(&self) -> u64 {
        self.store
            .saturating_add(self.scratch.max(self.export_beside_store()))
    }

    /// What the export adds beside the store while the output is written:
    /// its scratch, less what it frees of the store.
    pub fn export_beside_store(&self) -> u64 {
        self.export_scratch.saturating_sub(self.freed_at_export)
    }

    /// What one volume holding the scratch directory and the output holds
    /// at the peak: the stages' or the export's, whichever is larger.
    pub fn one_volume(&self) -> u64 {
        let export = (self.export_scratch.saturating_add(self.output_dir()))
            .saturating_sub(self.freed_at_export);
        self.store.saturating_add(self.scratch.max(export))
    }

    /// What the output's directory holds at the peak: the output and the
    /// scratch beside it.
    pub fn output_dir(&self) -> u64 {
        self.output.saturating_add(self.beside_output)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A kernel's disk figures: scratch at the stages' peak and at the
    /// export, checkpoints, output and beside it.
    fn cost(scratch: [u64; 3], output: [u64; 2]) -> KernelCost {
        KernelCost {
            bytes_per_point: 360,
            global_per_point: 0,
            contracts_boundaries: false,
            resident_per_point: 0.0,
            window_bytes_per_point: 0,
            scratch_per_point: scratch[0],
            export_scratch_per_point: scratch[1],
            checkpoint_per_point: scratch[2],
            external_scratch_saving: 0,
            export_frees_positions: false,
            output_per_point: output[0],
            beside_output_per_point: output[1],
            parallel_in_tile: false,
            margin_spacings: 0.0,
            resident_bytes: 0,
        }
    }

    #[test]
    fn sums_per_point_figures_without_overflow() {
        let cost = cost([84, 84, 0], [37, 3]);
        let plan = DiskPlan::new(1_000_000, 44, &cost);
        assert_eq!(plan.scratch_dir(), 128_000_000);
        assert_eq!(plan.output_dir(), 40_000_000);
        assert_eq!(plan.one_volume(), 168_000_000);
        assert_eq!(DiskPlan::new(u64::MAX, 44, &cost).scratch_dir(), u64::MAX);
        assert_eq!(DiskPlan::new(u64::MAX, 44, &cost).one_volume(), u64::MAX);
    }

    #[test]
    fn the_output_comes_on_top_of_the_export_not_of_the_stages() {
        let cost = cost([44, 30, 40], [20, 0]);
        let plain = DiskPlan::new(1000, 16, &cost);
        assert_eq!(plain.scratch_dir(), 60_000);
        assert_eq!(plain.one_volume(), 66_000);
        // A run directory keeps its checkpoints through the export.
        let kept = DiskPlan::new(1000, 16, &cost.in_run_dir());
        assert_eq!(kept.scratch_dir(), 100_000);
        assert_eq!(kept.one_volume(), 106_000);
        assert_eq!(cost.in_run_dir().in_run_dir(), cost.in_run_dir());
    }

    #[test]
    fn freed_positions_come_off_the_export_only_and_not_in_a_run_dir() {
        let cost = KernelCost {
            export_frees_positions: true,
            ..cost([44, 30, 40], [20, 0])
        };
        let plain = DiskPlan::new(1000, 16, &cost);
        assert_eq!(plain.freed_at_export, 12_000);
        // The stages' peak (16 + 44) now passes the export's (16 + 30 + 20 - 12).
        assert_eq!(plain.one_volume(), 60_000);
        assert_eq!(plain.scratch_dir(), 60_000);
        let shrunk = DiskPlan::new(
            1000,
            16,
            &KernelCost {
                scratch_per_point: 20,
                ..cost
            },
        );
        assert_eq!(shrunk.one_volume(), 16_000 + 38_000);
        assert_eq!(shrunk.scratch_dir(), 16_000 + 20_000);
        let kept = DiskPlan::new(
            1000,
            16,
            &KernelCost {
                scratch_per_point: 20,
                ..cost
            }
            .in_run_dir(),
        );
        assert_eq!(kept.freed_at_export, 0);
        assert_eq!(kept.one_volume(), 16_000 + 30_000 + 40_000 + 20_000);
    }

    #[test]
    fn an_external_global_pass_plans_its_own_scratch() {
        let cost = KernelCost {
            global_per_point: 6,
            external_scratch_saving: 12,
            ..cost([44, 30, 0], [20, 0])
        };
        let budget = crate::memory::MemoryBudget::new(256 << 20, 2);
        let fits = (256u64 << 20).saturating_sub(crate::memory::BASE_BYTES) / 2 / 6;
        assert_eq!(cost.under_budget(&budget, fits).scratch_per_point, 44);
        assert_eq!(cost.under_budget(&budget, fits + 1).scratch_per_point, 32);
        // Applied once: the saving is spent.
        let once = cost.under_budget(&budget, fits + 1);
        assert_eq!(once.under_budget(&budget, fits + 1), once);
        // A kernel without a global pass has nothing to save.
        let none = KernelCost {
            global_per_point: 0,
            ..cost
        };
        assert_eq!(none.under_budget(&budget, u64::MAX).scratch_per_point, 44);
    }
}
