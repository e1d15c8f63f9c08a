//! The disk a run needs at its peak, from the same declared costs as the
//! memory plan: the store built from the input, the stages' scratch beside
//! it (columns, checkpointed tiles, spills) and the output. `info --plan`
//! prints it; a run compares it with the free space before it starts.

use super::plan::KernelCost;

/// Bytes on disk at a run's peak.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DiskPlan {
    /// The point store (0 when the input already is one).
    pub store: u64,
    /// The stages' scratch beside the store.
    pub scratch: u64,
    /// The output file.
    pub output: u64,
    /// Unnamed scratch beside the output while it is written.
    pub beside_output: u64,
}

impl DiskPlan {
    /// The plan for `points` points whose store takes `store_per_point`
    /// bytes each, under a kernel costing `cost`.
    pub fn new(points: u64, store_per_point: u64, cost: &KernelCost) -> Self {
        DiskPlan {
            store: points.saturating_mul(store_per_point),
            scratch: points.saturating_mul(cost.scratch_per_point),
            output: points.saturating_mul(cost.output_per_point),
            beside_output: points.saturating_mul(cost.beside_output_per_point),
        }
    }

    /// What the scratch directory holds at the peak: the store and the
    /// stages' scratch.
    pub fn scratch_dir(&self) -> u64 {
        self.store.saturating_add(self.scratch)
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

    #[test]
    fn sums_per_point_figures_without_overflow() {
        let cost = KernelCost {
            bytes_per_point: 360,
            global_per_point: 0,
            contracts_boundaries: false,
            resident_per_point: 0.0,
            window_bytes_per_point: 0,
            scratch_per_point: 84,
            output_per_point: 37,
            beside_output_per_point: 3,
            parallel_in_tile: false,
            margin_spacings: 0.0,
            resident_bytes: 0,
        };
        let plan = DiskPlan::new(1_000_000, 44, &cost);
        assert_eq!(plan.scratch_dir(), 128_000_000);
        assert_eq!(plan.output_dir(), 40_000_000);
        assert_eq!(DiskPlan::new(u64::MAX, 44, &cost).scratch_dir(), u64::MAX);
    }
}
