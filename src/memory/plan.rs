//! The memory plan of a run: every size the run uses (tile target, histogram
//! cells, scatter buffers, export window) derived from `--mem`, the thread
//! count, the point count and what the kernel declares it costs, and checked
//! against the promise before the work starts. A budget no plan fits is an
//! error that names the smallest one that does.
//!
//! The model (ARCHITECTURE.md, "Memory") per stage, beside the fixed costs:
//! - histogram: at most `histogram_cells` occupied cells, 36 bytes each at
//!   the peak (the grid coarsens to fit, see `store::cells`);
//! - scatter: `scatter_buffer` bytes of per-tile buffers in all;
//! - tiles: `threads + 1` tiles in flight (one for a kernel parallel
//!   inside a tile), each `tile_points` core points and up to half as
//!   many again in its margin (more where a kernel declares a wide margin,
//!   [`KernelCost::margin_spacings`]), at the kernel's bytes per loaded
//!   point;
//! - global pass: the kernel's per-point state when it fits half the
//!   budget; otherwise the contracted graph of the external pass, whose
//!   nodes are the tiles' boundary points: about `NODES_PER_SQRT_TILE` /
//!   sqrt(tile points) of all points on a scanned surface, at
//!   `BYTES_PER_NODE` each;
//! - export: a window of `window_points` input-order records.

use super::budget::BASE_BYTES;
use super::MemoryBudget;

/// Fewest core points a tile may hold: below this the margins (a few
/// neighbourhood radii on every side) outweigh the core.
pub const MIN_TILE_POINTS: u64 = 8192;
/// Loaded points per core point the tile sizes allow for (the margin).
pub const MARGIN_FACTOR: f64 = 1.5;
/// Boundary nodes of the external orientation per point, times the square
/// root of the tile size: 10.4 measured on the 10M-point noisy dragon with
/// tiles of 17k, 77k and 312k points (k = 12); 13 allows for rougher scans.
pub(crate) const NODES_PER_SQRT_TILE: f64 = 13.0;
/// Bytes per node of the external orientation's global solve (the rank
/// table, the union-find, the accepted-edge bits).
pub(crate) const BYTES_PER_NODE: u64 = 10;
/// Peak bytes per occupied histogram cell.
pub(crate) const BYTES_PER_CELL: u64 = 36;

/// What a tile kernel and the passes around it cost, as it declares.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KernelCost {
    /// Peak bytes per loaded point while a tile runs.
    pub bytes_per_point: u64,
    /// Bytes per point a global pass keeps in memory when they fit half the
    /// budget (0: none); otherwise the pass goes external.
    pub global_per_point: u64,
    /// Whether the external global pass contracts tile boundaries (its
    /// nodes then count, see the module doc).
    pub contracts_boundaries: bool,
    /// Bytes per point of state that must stay in memory beside the tiles
    /// of a later pass, with no external path (the small-piece filter's
    /// sets beside the marching-cubes tiles, the projection's seam frames
    /// until its seam pass); never at once with the global pass's state.
    pub resident_per_point: f64,
    /// Bytes per point of an output window (0: no input-order output).
    pub window_bytes_per_point: u64,
    /// Scratch disk per point at the run's peak beside the store (columns,
    /// spills, and checkpointed tiles where [`Self::checkpoint_per_point`]
    /// does not count them apart); the store's own bytes depend on the
    /// input (`store::store_bytes_per_point`).
    pub scratch_per_point: u64,
    /// Of that, what is still beside the store while the output is written
    /// (the columns the export reads, its reorder file): the output comes
    /// on top of this, not of the stages' peak, when both share a volume.
    pub export_scratch_per_point: u64,
    /// Scratch per point a run directory adds to a plain run's (the
    /// checkpointed tile outputs it keeps so a killed run resumes), until
    /// the run is done; see [`Self::in_run_dir`].
    pub checkpoint_per_point: u64,
    /// Of [`Self::scratch_per_point`], what the global pass does not write
    /// when it goes external (the normals' forest packed per tile, about
    /// 11 B an edge, where the in-memory union-find's merged records take
    /// 24): the disk plan takes it off then ([`Self::under_budget`]).
    pub external_scratch_saving: u64,
    /// The export frees the store's tile-ordered positions before the
    /// output grows (a per-point run's scratch store,
    /// `PointStore::release_positions`): the disk plan counts the store
    /// without them while the output is written.
    pub export_frees_positions: bool,
    /// Output file bytes per input point, roughly.
    pub output_per_point: u64,
    /// Unnamed scratch bytes per input point beside the output while it is
    /// written (the mesh audit's runs and sets, `mesh::audit`).
    pub beside_output_per_point: u64,
    /// The kernel keeps every thread busy inside one tile (the projection's
    /// lattice jobs run in parallel), so tiles run one at a time and the
    /// plan gives that one tile what `threads + 1` would share: larger
    /// tiles, whose margins are a smaller share of the work.
    pub parallel_in_tile: bool,
    /// The kernel's margin in mean spacings when it is wide enough to set
    /// the tile sizes (0: the flat [`MARGIN_FACTOR`]). A tile of `c` core
    /// points on a scanned surface spans about `sqrt(c)` spacings, so it
    /// loads `((sqrt(c) + 2 m) / sqrt(c))^2` points per core point: the
    /// smaller the budget, the larger that share.
    pub margin_spacings: f64,
    /// Bytes of state kept beside the tiles whatever the point count (the
    /// `--closed` winding tree, whose size is capped).
    pub resident_bytes: u64,
}

impl KernelCost {
    /// The cost of the same run in a run directory, whose checkpointed
    /// tiles stay beside the store through the export.
    pub fn in_run_dir(self) -> Self {
        KernelCost {
            scratch_per_point: self.scratch_per_point + self.checkpoint_per_point,
            export_scratch_per_point: self.export_scratch_per_point + self.checkpoint_per_point,
            checkpoint_per_point: 0,
            // The store of a run directory is kept: its positions too.
            export_frees_positions: false,
            ..self
        }
    }

    /// The cost of the same run under `budget` for `points` points: a
    /// global pass that does not fit in memory goes external, and its
    /// scratch is then the external path's (the same decision
    /// [`MemoryPlan::new`] and the kernels make, `MemoryBudget::holds`).
    pub fn under_budget(self, budget: &MemoryBudget, points: u64) -> Self {
        let external = self.global_per_point > 0 && !budget.holds(points, self.global_per_point);
        KernelCost {
            scratch_per_point: match external {
                true => self
                    .scratch_per_point
                    .saturating_sub(self.external_scratch_saving),
                false => self.scratch_per_point,
            },
            external_scratch_saving: 0,
            ..self
        }
    }

    /// Tiles running at once for `threads` threads.
    pub fn workers(&self, threads: usize) -> usize {
        if self.parallel_in_tile {
            1
        } else {
            threads.max(1)
        }
    }

    /// Loaded points per core point the plan allows for in tiles of `core`
    /// points.
    pub fn loaded_per_core(&self, core: u64) -> f64 {
        let side = (core.max(1) as f64).sqrt();
        let grown = (side + 2.0 * self.margin_spacings.max(0.0)) / side;
        (grown * grown).max(MARGIN_FACTOR)
    }

    /// Largest tile whose `in_flight` copies, margins included, fit `free`
    /// bytes: the flat factor's size, or smaller where the margin is wide
    /// (`in_flight * bpp * (sqrt(c) + 2 m)^2 <= free`).
    fn tile_points(&self, budget: MemoryBudget, reserved: u64, in_flight: u64) -> u64 {
        let flat = budget.tile_points(self.bytes_per_point, MARGIN_FACTOR, reserved, in_flight);
        if self.margin_spacings <= 0.0 {
            return flat;
        }
        let free = budget.bytes.saturating_sub(BASE_BYTES + reserved) / in_flight.max(1);
        let side = (free as f64 / self.bytes_per_point.max(1) as f64).sqrt();
        let core = (side - 2.0 * self.margin_spacings).max(0.0);
        flat.min((core * core) as u64)
    }

    /// Tiles loaded, running or waiting at once for `threads` threads: one
    /// more than run, so the next loads while the others run, except when
    /// one tile takes every thread (loading a tile costs little beside it).
    pub fn in_flight(&self, threads: usize) -> usize {
        if self.parallel_in_tile {
            1
        } else {
            threads.max(1) + 1
        }
    }
}

/// Why no plan fits.
#[derive(Debug, thiserror::Error, PartialEq)]
#[non_exhaustive]
pub enum BudgetError {
    /// No plan fits the budget: the run needs at least `needed` bytes.
    #[error(
        "memory budget {budget} is too small{for_points}: this run needs at least {needed} ({reason})",
        budget = crate::units::human_bytes(*.budget),
        needed = crate::units::human_bytes(*.needed),
        for_points = if *.points > 0 { format!(" for {} points", .points) } else { String::new() }
    )]
    TooSmall {
        /// The budget, in bytes.
        budget: u64,
        /// Points the run processes (0 when not known yet).
        points: u64,
        /// The smallest budget that fits, in bytes.
        needed: u64,
        /// Which part of the run does not fit.
        reason: &'static str,
    },
}

/// Every size a run uses, fitted to the promise.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MemoryPlan {
    /// The budget the plan fits.
    pub budget: MemoryBudget,
    /// Points of the run the plan is sized for.
    pub points: u64,
    /// Core points per tile the planner aims for.
    pub tile_points: u64,
    /// Whether the global pass keeps its per-point state in memory.
    pub global_in_memory: bool,
    /// Bytes kept beside the tiles for state that grows with the points.
    pub reserved: u64,
    /// Most occupied histogram cells held at once while the store is laid out.
    pub histogram_cells: usize,
    /// Bytes of per-tile write buffers during the scatter pass, in total.
    pub scatter_buffer: usize,
    /// Input-order records held at once when exporting.
    pub window_points: u64,
    /// Estimated nodes of the external global pass (0 in memory).
    pub nodes: u64,
}

impl MemoryPlan {
    /// The plan for `points` points under `budget`, or why none fits.
    pub fn new(budget: MemoryBudget, points: u64, cost: &KernelCost) -> Result<Self, BudgetError> {
        Self::assess(budget, points, cost).map_err(|reason| BudgetError::TooSmall {
            budget: budget.bytes,
            points,
            needed: Self::minimum_budget(budget.threads, points, cost),
            reason,
        })
    }

    fn assess(budget: MemoryBudget, points: u64, cost: &KernelCost) -> Result<Self, &'static str> {
        let free = budget.bytes.saturating_sub(BASE_BYTES);
        let global_in_memory = budget.holds(points, cost.global_per_point);
        let resident = (points as f64 * cost.resident_per_point) as u64 + cost.resident_bytes;
        if resident > free / 2 {
            return Err("state the kernel keeps for the whole run (the piece filter's sets, the seam frames)");
        }
        // The global pass follows the kernel pass that resident state
        // belongs to (or precedes it): they never hold memory at once.
        let global = if global_in_memory {
            points * cost.global_per_point
        } else {
            0
        };
        let reserved = resident.max(global);
        let in_flight = cost.in_flight(budget.threads) as u64;
        let tile_points = cost.tile_points(budget, reserved, in_flight);
        if free == 0 || tile_points < MIN_TILE_POINTS {
            return Err("tiles of at least 8192 points beside the fixed costs");
        }
        let nodes = if global_in_memory || !cost.contracts_boundaries {
            0
        } else {
            external_nodes(points, tile_points)
        };
        if nodes * BYTES_PER_NODE > free {
            return Err("the orientation's contracted tile boundaries");
        }
        Ok(MemoryPlan {
            budget,
            points,
            tile_points,
            global_in_memory,
            reserved,
            histogram_cells: histogram_cells(budget),
            scatter_buffer: scatter_buffer(budget),
            window_points: (free / 4 / cost.window_bytes_per_point.max(1)).max(1 << 12),
            nodes,
        })
    }

    /// The smallest budget (to 1 MiB) for which [`MemoryPlan::new`] succeeds.
    pub fn minimum_budget(threads: usize, points: u64, cost: &KernelCost) -> u64 {
        let fits =
            |mib: u64| Self::assess(MemoryBudget::new(mib << 20, threads), points, cost).is_ok();
        let (mut lo, mut hi) = (BASE_BYTES >> 20, 1u64 << 24);
        while lo < hi {
            let mid = (lo + hi) / 2;
            if fits(mid) {
                hi = mid;
            } else {
                lo = mid + 1;
            }
        }
        lo << 20
    }

    /// Tiles in flight for a store whose largest tile holds `largest` core
    /// points: `cost.in_flight` when that many such tiles fit the plan, else
    /// fewer (a store built under a larger budget), down to one; none
    /// fitting is an error naming the budget needed.
    pub(crate) fn tiles_in_flight(
        &self,
        cost: &KernelCost,
        largest: u64,
    ) -> Result<usize, BudgetError> {
        let fit = self.tile_shares(cost, largest);
        if fit == 0 {
            let per_tile = self.tile_bytes(cost, largest);
            return Err(BudgetError::TooSmall {
                budget: self.budget.bytes,
                points: self.points,
                needed: (BASE_BYTES + self.reserved + per_tile).div_ceil(1 << 20) << 20,
                reason: "the store's largest tile: the store was tiled for a larger budget",
            });
        }
        Ok(cost.in_flight(self.budget.threads).min(fit))
    }

    /// How many tiles of `largest` core points, margins as planned, the
    /// plan's free memory holds at once. Tiles forced smaller than the
    /// budget allows (`--tile-points`) leave room for more than the tiles
    /// in flight, and a tile needing more than planned may use it.
    pub(crate) fn tile_shares(&self, cost: &KernelCost, largest: u64) -> usize {
        (self.tile_room() / self.tile_bytes(cost, largest).max(1)) as usize
    }

    /// The plan's free memory, which the tiles in flight share
    /// (`pipeline::shares`).
    pub(crate) fn tile_room(&self) -> u64 {
        self.budget.bytes.saturating_sub(BASE_BYTES + self.reserved)
    }

    /// Bytes one tile in flight may use: the largest tile's core points
    /// with the margin allowed for, at the kernel's bytes per point.
    pub(crate) fn tile_bytes(&self, cost: &KernelCost, largest: u64) -> u64 {
        (largest as f64 * cost.loaded_per_core(largest) * cost.bytes_per_point as f64) as u64
    }

    /// Estimated peak of each stage beside the fixed costs, for `info --plan`.
    pub fn stages(&self, cost: &KernelCost) -> Vec<(&'static str, u64)> {
        let tiles = cost.in_flight(self.budget.threads) as f64
            * self.tile_points as f64
            * cost.loaded_per_core(self.tile_points)
            * cost.bytes_per_point as f64;
        let global = if self.global_in_memory {
            self.reserved
        } else {
            self.nodes * BYTES_PER_NODE
        };
        vec![
            ("histogram", self.histogram_cells as u64 * BYTES_PER_CELL),
            ("scatter", self.scatter_buffer as u64),
            ("tiles", tiles as u64),
            ("global pass", global),
            (
                "export window",
                self.window_points * cost.window_bytes_per_point,
            ),
        ]
    }
}

/// Estimated nodes of the external pass for tiles of `tile_points`.
fn external_nodes(points: u64, tile_points: u64) -> u64 {
    let share = (NODES_PER_SQRT_TILE / (tile_points.max(1) as f64).sqrt()).min(1.0);
    (points as f64 * share) as u64
}

/// Histogram cells the budget holds: half of what is free.
pub(crate) fn histogram_cells(budget: MemoryBudget) -> usize {
    (budget.bytes.saturating_sub(BASE_BYTES) / 2 / BYTES_PER_CELL).max(1024) as usize
}

/// Scatter buffers: an eighth of the budget, at most 64 MiB (larger ones
/// buy nothing: the writes are already long).
pub(crate) fn scatter_buffer(budget: MemoryBudget) -> usize {
    (budget.bytes / 8).min(64 << 20) as usize
}

#[cfg(test)]
mod tests {
    use super::*;

    fn normals() -> KernelCost {
        KernelCost {
            bytes_per_point: 360,
            global_per_point: 6,
            contracts_boundaries: true,
            resident_per_point: 0.0,
            window_bytes_per_point: 48,
            scratch_per_point: 94,
            export_scratch_per_point: 94,
            checkpoint_per_point: 0,
            external_scratch_saving: 0,
            export_frees_positions: false,
            output_per_point: 37,
            beside_output_per_point: 0,
            parallel_in_tile: false,
            margin_spacings: 0.0,
            resident_bytes: 0,
        }
    }

    #[test]
    fn the_minimum_budget_is_the_smallest_that_plans() {
        for points in [1_000u64, 10_000_000, 100_000_000, 1_000_000_000] {
            for threads in [1, 2, 8] {
                let min = MemoryPlan::minimum_budget(threads, points, &normals());
                let ok = MemoryPlan::new(MemoryBudget::new(min, threads), points, &normals());
                assert!(ok.is_ok(), "{points} points, {threads} threads: {min}");
                let below = MemoryBudget::new(min - (1 << 20), threads);
                let err = MemoryPlan::new(below, points, &normals());
                assert!(
                    matches!(err, Err(BudgetError::TooSmall { needed, .. }) if needed == min),
                    "{points} points, {threads} threads"
                );
            }
        }
    }

    #[test]
    fn oversized_tiles_run_fewer_at_a_time() {
        let budget = MemoryBudget::new(256 << 20, 2);
        let plan = MemoryPlan::new(budget, 100_000_000, &normals()).unwrap();
        let all = plan.tiles_in_flight(&normals(), plan.tile_points).unwrap();
        assert_eq!(all, 3);
        let one = plan.tiles_in_flight(&normals(), plan.tile_points * 5 / 2);
        assert_eq!(one, Ok(1));
        assert!(plan
            .tiles_in_flight(&normals(), plan.tile_points * 4)
            .is_err());
    }

    /// The shares a reload may take are the budget's room for tiles: as
    /// many as the tiles in flight for tiles of the planned size, more for
    /// tiles forced smaller, and never more bytes than the room.
    #[test]
    fn smaller_tiles_leave_more_shares() {
        let budget = MemoryBudget::new(256 << 20, 2);
        let plan = MemoryPlan::new(budget, 100_000_000, &normals()).unwrap();
        let planned = plan.tile_shares(&normals(), plan.tile_points);
        assert_eq!(planned, 3);
        let tenth = plan.tile_points / 10;
        let shares = plan.tile_shares(&normals(), tenth);
        assert!(shares >= 25, "{shares}");
        let room = budget.bytes - BASE_BYTES - plan.reserved;
        assert!(shares as u64 * plan.tile_bytes(&normals(), tenth) <= room);
    }

    #[test]
    fn tiles_grow_with_the_budget_not_with_the_points() {
        let at = |mib: u64, points: u64| {
            MemoryPlan::new(MemoryBudget::new(mib << 20, 2), points, &normals())
                .map(|p| p.tile_points)
                .unwrap_or(0)
        };
        assert_eq!(at(512, 100_000_000), at(512, 1_000_000_000));
        assert!(at(512, 1_000_000_000) > 0);
        assert!(at(512, 100_000_000) > at(256, 100_000_000));
        // In memory at 10M (its union-find reserved), external at 100M.
        assert!(at(256, 10_000_000) < at(256, 100_000_000));
    }

    #[test]
    fn one_tile_in_flight_gets_the_budget_of_all() {
        let budget = MemoryBudget::new(512 << 20, 2);
        let shared = MemoryPlan::new(budget, 10_000_000, &normals()).unwrap();
        let alone = KernelCost {
            parallel_in_tile: true,
            ..normals()
        };
        let plan = MemoryPlan::new(budget, 10_000_000, &alone).unwrap();
        assert_eq!(plan.tiles_in_flight(&alone, plan.tile_points), Ok(1));
        assert_eq!((alone.workers(2), normals().workers(2)), (1, 2));
        let ratio = plan.tile_points as f64 / shared.tile_points as f64;
        assert!((2.9..3.1).contains(&ratio), "{ratio}");
    }

    #[test]
    fn a_wide_margin_shrinks_small_budgets_tiles_and_fits_them() {
        let wide = KernelCost {
            margin_spacings: 140.0,
            global_per_point: 0,
            ..normals()
        };
        for mib in [128u64, 192, 256, 512, 4096] {
            let budget = MemoryBudget::new(mib << 20, 2);
            let narrow = KernelCost {
                margin_spacings: 0.0,
                ..wide
            };
            let flat = MemoryPlan::new(budget, 10_000_000, &narrow).unwrap();
            let Ok(plan) = MemoryPlan::new(budget, 10_000_000, &wide) else {
                // Three tiles of 360 B per point and a 140-spacing margin
                // do not fit 128 MiB: refused, never overrun.
                assert!(mib <= 128, "{mib} MiB does not plan");
                continue;
            };
            assert!(plan.tile_points <= flat.tile_points);
            let c = plan.tile_points;
            let loaded = c as f64 * wide.loaded_per_core(c);
            let side = (c as f64).sqrt();
            assert!(loaded >= (side + 280.0).powi(2) * 0.999, "{mib}: {loaded}");
            let tiles = 3.0 * loaded * wide.bytes_per_point as f64;
            assert!(tiles <= (budget.bytes - BASE_BYTES) as f64, "{mib} MiB");
        }
        // Large tiles keep at least the flat allowance.
        assert_eq!(wide.loaded_per_core(1 << 40), MARGIN_FACTOR);
    }
}
