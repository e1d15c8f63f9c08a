//! The shared tile pipeline: schedules tile jobs on worker threads, bounds the
//! tiles in flight (and so the memory), reorders results into tile order and
//! hands them to the kernel's seam policy (`run_tiles`, the lower layer); a
//! stage declared as a type (`stage`: `Stage`, `Seam`) runs over it with
//! `run_stage`. It knows nothing of geometry.

mod codec;
mod kernel;
mod options;
mod run;
mod shares;
mod stage;
mod workspace;

#[cfg(test)]
mod budget_tests;

pub use codec::Codec;
pub use kernel::{KernelError, TileFault, TileKernel};
pub use options::RunOptions;
pub use run::{run_tiles, RunStats};
pub use stage::{run_stage, Seam, Stage, StageColumns, StageParams};
pub use workspace::{reclaim, reclaimed_note, Prepared, RunSettings, WorkspaceError};
// What a kernel is handed: a tile's points and declared columns. Public so
// that a kernel can live outside the crate.
pub use crate::tiling::{MissingColumns, TileColumn, TilePoints, Values};
// The run's memory and progress live below every layer that uses them; a
// kernel finds them here beside the pipeline that takes them.
pub use crate::memory::{BudgetError, KernelCost, MemoryBudget, MemoryPlan};
pub use crate::progress::{NoProgress, Progress};

/// Errors of the tile pipeline.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PipelineError {
    /// Reading the store failed.
    #[error(transparent)]
    Store(#[from] crate::store::StoreError),
    /// Reading or writing a file failed.
    #[error(transparent)]
    Io(#[from] crate::io::IoError),
    /// A kernel failed on a tile.
    #[error("tile {tile}: {source}")]
    Kernel {
        /// 0-based index of the tile.
        tile: usize,
        /// The kernel's error.
        #[source]
        source: Box<dyn std::error::Error + Send + Sync>,
    },
    /// A kernel kept asking for more margin than a reload can give.
    #[error("tile {tile}: margin {margin} is short but the kernel asked for {needed}")]
    MarginStuck {
        /// 0-based index of the tile.
        tile: usize,
        /// The margin loaded, in the store's coordinate units.
        margin: f64,
        /// The margin the kernel asked for.
        needed: f64,
    },
    /// A tile's margin grew past what the memory promise can hold.
    #[error("tile {tile}: its margin {margin:.3e} loads {points} points, which need about {need_mib} MiB, more than the {room_mib} MiB the budget holds for tiles; a larger --mem gives it room (and larger tiles, whose margins are a smaller share, unless --tile-points fixes their size)")]
    OverBudget {
        /// 0-based index of the tile.
        tile: usize,
        /// The margin loaded, in the store's coordinate units.
        margin: f64,
        /// Points loaded.
        points: usize,
        /// What the kernel says the tile needs, MiB.
        need_mib: u64,
        /// The plan's room for the tiles in flight, MiB.
        room_mib: u64,
    },
    /// A worker thread ended without handing back its tile's result (it panicked).
    #[error("a worker thread stopped without a result")]
    WorkerLost,
    /// The seam policy failed (its stitcher's typed error, kept).
    #[error(transparent)]
    Seam(Box<dyn std::error::Error + Send + Sync>),
    /// The job this process was started for is done (`--until`, a tile
    /// job): not a failure.
    #[error("stopped at stage `{stage}` as the job asked")]
    Stopped {
        /// The stage the job stopped at ([`TileKernel::name`]).
        stage: &'static str,
    },
    /// A job needs a stage whose tile jobs have not all finished.
    #[error("stage `{stage}` has {done} of {total} tiles done: its tile jobs must finish before this job")]
    StageIncomplete {
        /// The unfinished stage ([`TileKernel::name`]).
        stage: &'static str,
        /// Its tiles done.
        done: usize,
        /// Its tiles in all.
        total: usize,
    },
    /// A tile job was asked of a stage that keeps no tile results.
    #[error("stage `{stage}` keeps no tile results, so it cannot run as tile jobs")]
    NotSplittable {
        /// The stage ([`TileKernel::name`]).
        stage: &'static str,
    },
    /// A stage's kernel does not answer to the stage's declarations (its
    /// name is not the stage's id, or it reads other columns): a stage
    /// defined wrongly, refused before any column is made.
    #[error("stage `{stage}`: its kernel {what}")]
    KernelNotTheStages {
        /// The stage ([`crate::pipeline::Stage::ID`]).
        stage: &'static str,
        /// What differs.
        what: &'static str,
    },
    /// A saved tile result of a resumable run cannot be read back.
    #[error("tile {tile} of stage `{stage}`: its saved result does not decode ({source})")]
    Codec {
        /// The stage ([`TileKernel::name`]).
        stage: &'static str,
        /// 0-based index of the tile.
        tile: usize,
        /// The encoder's or decoder's error.
        #[source]
        source: Box<dyn std::error::Error + Send + Sync>,
    },
}

impl PipelineError {
    /// A seam policy's own error, kept typed.
    pub(crate) fn seam(e: impl std::error::Error + Send + Sync + 'static) -> Self {
        PipelineError::Seam(Box::new(e))
    }
}
