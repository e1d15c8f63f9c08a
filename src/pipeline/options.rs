//! How a run of tiles is sized: worker threads, tiles in flight and the
//! memory promise global passes plan by.

use crate::memory::{BudgetError, KernelCost, MemoryBudget, MemoryPlan};

/// How many workers run tiles, and how many tiles may be in memory.
#[derive(Clone, Copy, Debug)]
pub struct RunOptions {
    /// Worker threads running tiles (at least 1).
    pub threads: usize,
    /// Tiles loaded, running or waiting in the reorder buffer at once.
    pub in_flight: usize,
    /// The memory promise global passes plan by (`None`: unbounded, every
    /// pass keeps its state in memory).
    pub budget: Option<MemoryBudget>,
    /// Bytes the plan gives each tile in flight (`None`: no plan), for
    /// kernels whose tiles can need more (`TileKernel::bytes_for`).
    pub tile_bytes: Option<u64>,
    /// Bytes the plan holds for the tiles in flight at once (`None`:
    /// `in_flight` times `tile_bytes`): a tile needing more than
    /// `tile_bytes` takes more of it (`pipeline::shares`).
    pub tile_room: Option<u64>,
}

impl RunOptions {
    /// `threads` workers, no memory promise.
    pub fn new(threads: usize) -> Self {
        let threads = threads.max(1);
        let in_flight = threads + 1;
        RunOptions {
            threads,
            in_flight,
            budget: None,
            tile_bytes: None,
            tile_room: None,
        }
    }

    /// Options under `plan` for a store whose largest tile holds `largest`
    /// core points: fewer tiles in flight when that many do not fit.
    pub fn planned(
        plan: &MemoryPlan,
        cost: &KernelCost,
        largest: u64,
    ) -> Result<Self, BudgetError> {
        let opts = RunOptions::new(cost.workers(plan.budget.threads)).within(plan.budget);
        let in_flight = plan.tiles_in_flight(cost, largest)?;
        Ok(RunOptions {
            in_flight,
            tile_bytes: Some(plan.tile_bytes(cost, largest)),
            tile_room: Some(
                plan.tile_room()
                    .max(in_flight as u64 * plan.tile_bytes(cost, largest)),
            ),
            ..opts
        })
    }

    /// The same options under the memory promise `budget`.
    pub fn within(self, budget: MemoryBudget) -> Self {
        RunOptions {
            budget: Some(budget),
            ..self
        }
    }

    /// Whether a global pass may keep `bytes_per_point` per point in memory
    /// (see [`MemoryBudget::holds`]).
    pub fn holds(&self, points: u64, bytes_per_point: u64) -> bool {
        self.budget.is_none_or(|b| b.holds(points, bytes_per_point))
    }
}
