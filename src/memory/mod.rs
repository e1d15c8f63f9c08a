//! The memory promise (`--mem`): the budget, the plan that derives every
//! size a run uses from it and from what a kernel declares it costs, the
//! disk the same costs need, and the process's measured peak. A bottom
//! layer: it knows no store, tile or kernel, only numbers.

mod budget;
mod disk;
mod machine;
pub mod plan;
mod plan_table;

pub use budget::{
    peak_rss_bytes, within_promise, MachineMemory, MemoryBudget, PeakOver, BASE_BYTES,
};
pub use disk::DiskPlan;
pub use machine::{cores, too_many_threads, too_much_memory, BeyondMachine, MAX_THREADS_PER_CORE};
pub use plan::{BudgetError, KernelCost, MemoryPlan};
pub use plan_table::PlanTable;
