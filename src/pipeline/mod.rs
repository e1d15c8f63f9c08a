//! The shared tile pipeline: schedules tile jobs on worker threads, bounds the
//! tiles in flight (and so the memory), reorders results into tile order and
//! hands them to the kernel's seam policy. It knows nothing of geometry.

mod codec;
mod kernel;
mod options;
mod run;

pub use codec::Codec;
pub use kernel::{KernelError, TileKernel};
pub use options::RunOptions;
pub use run::{run_tiles, RunStats};
// The run's memory and progress live below every layer that uses them; a
// kernel finds them here beside the pipeline that takes them.
pub use crate::memory::{BudgetError, KernelCost, MemoryBudget, MemoryPlan};
pub use crate::progress::{NoProgress, Progress};

#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PipelineError {
    #[error(transparent)]
    Store(#[from] crate::store::StoreError),
    #[error(transparent)]
    Io(#[from] crate::io::IoError),
    #[error("tile {tile}: {source}")]
    Kernel {
        tile: usize,
        #[source]
        source: Box<dyn std::error::Error + Send + Sync>,
    },
    #[error("tile {tile}: margin {margin} is short but the kernel asked for {needed}")]
    MarginStuck {
        tile: usize,
        margin: f64,
        needed: f64,
    },
    #[error("a worker thread stopped without a result")]
    WorkerLost,
    /// The seam policy failed (its stitcher's typed error, kept).
    #[error(transparent)]
    Seam(Box<dyn std::error::Error + Send + Sync>),
    /// The job this process was started for is done (`--until`, a tile
    /// job): not a failure.
    #[error("stopped at stage `{stage}` as the job asked")]
    Stopped { stage: String },
    #[error("stage `{stage}` has {done} of {total} tiles done: its tile jobs must finish before this job")]
    StageIncomplete {
        stage: String,
        done: usize,
        total: usize,
    },
    #[error("stage `{stage}` keeps no tile results, so it cannot run as tile jobs")]
    NotSplittable { stage: String },
    #[error("tile {tile} of stage `{stage}`: its saved result does not decode ({reason})")]
    Codec {
        stage: String,
        tile: usize,
        reason: String,
    },
}

impl PipelineError {
    /// A seam policy's own error, kept typed.
    pub(crate) fn seam(e: impl std::error::Error + Send + Sync + 'static) -> Self {
        PipelineError::Seam(Box::new(e))
    }
}
