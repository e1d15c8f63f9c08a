//! The plan of a run, as `info --plan` prints it before any run: tiles,
//! tiles in flight, the global pass's mode, the bytes of each stage, and
//! the disk the run needs at its peak. Numbers only, from the same plan a
//! run makes.

use super::plan::{BudgetError, KernelCost, MemoryPlan, MIN_TILE_POINTS};
use super::{DiskPlan, MemoryBudget, BASE_BYTES};
use crate::units::human_bytes;
use std::fmt;

/// The memory and disk plan of a run over `points` points under a budget.
#[derive(Clone, Debug)]
pub struct PlanTable {
    budget: MemoryBudget,
    points: u64,
    cost: KernelCost,
    plan: MemoryPlan,
    disk: DiskPlan,
}

impl PlanTable {
    /// The plan for `points` points of a kernel costing `cost` under
    /// `budget`, a point of the store to build taking `store_per_point`
    /// bytes on disk (0: the store exists); an error when no plan fits.
    pub fn new(
        budget: MemoryBudget,
        points: u64,
        store_per_point: u64,
        cost: KernelCost,
    ) -> Result<Self, BudgetError> {
        let plan = MemoryPlan::new(budget, points, &cost)?;
        let disk = DiskPlan::new(points, store_per_point, &cost.under_budget(&budget, points));
        Ok(PlanTable {
            budget,
            points,
            cost,
            plan,
            disk,
        })
    }

    /// The disk plan.
    pub fn disk(&self) -> &DiskPlan {
        &self.disk
    }

    fn global(&self) -> String {
        if self.cost.global_per_point == 0 {
            "none".to_string()
        } else if self.plan.global_in_memory {
            format!("in memory ({} B/point)", self.cost.global_per_point)
        } else {
            format!(
                "external (about {} contracted boundary nodes)",
                self.plan.nodes
            )
        }
    }
}

impl fmt::Display for PlanTable {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (points, cost, plan) = (self.points, &self.cost, &self.plan);
        let threads = self.budget.threads;
        let minimum = MemoryPlan::minimum_budget(threads, points, cost);
        writeln!(
            f,
            "plan for {} points, --mem {}, {} threads:",
            points,
            human_bytes(self.budget.bytes),
            threads
        )?;
        writeln!(f, "  smallest budget that plans: {}", human_bytes(minimum))?;
        writeln!(
            f,
            "  tiles: at most {} core points each (at least {MIN_TILE_POINTS}), about {} tiles; {} in flight, margins up to {:.1}x the core",
            plan.tile_points,
            points.div_ceil(plan.tile_points),
            cost.in_flight(threads),
            cost.loaded_per_core(plan.tile_points)
        )?;
        writeln!(f, "  global pass: {}", self.global())?;
        if cost.resident_per_point > 0.0 {
            writeln!(
                f,
                "  small-piece filter: about {} beside the marching-cubes tiles",
                human_bytes((points as f64 * cost.resident_per_point) as u64)
            )?;
        }
        for (stage, bytes) in plan.stages(cost) {
            writeln!(f, "  {stage:>14}: {}", human_bytes(bytes))?;
        }
        writeln!(f, "  fixed costs: {}", human_bytes(BASE_BYTES))?;
        let disk = &self.disk;
        write!(
            f,
            "disk at the peak: the store {}, scratch beside it {} ({} while the output is written), the output {} and scratch beside that {}; {} on one volume (about; --scratch-dir puts the first two elsewhere; a run directory adds {} of checkpoints)",
            human_bytes(disk.store),
            human_bytes(disk.scratch),
            human_bytes(disk.export_beside_store()),
            human_bytes(disk.output),
            human_bytes(disk.beside_output),
            human_bytes(disk.one_volume()),
            human_bytes(points.saturating_mul(cost.checkpoint_per_point)),
        )
    }
}
