//! Progress reporting: the library reports stages and counts through this
//! trait and never prints on its own; a caller picks where they go
//! ([`bars`]: indicatif bars on a terminal, as the CLI shows them).

mod bars;

pub use bars::{bars, Bars};

/// Receives progress of long-running stages. Implementations must be cheap:
/// `advance` is called from worker threads, often.
pub trait Progress: Sync {
    /// A stage starts; `total` is in the stage's own unit (points, tiles,
    /// bytes), 0 when unknown.
    fn begin(&self, stage: &str, total: u64);
    /// `n` more units of the current stage are done.
    fn advance(&self, n: u64);
    /// The current stage is over.
    fn end(&self);
}

/// Progress that goes nowhere (tests, `--quiet`).
#[derive(Clone, Copy, Debug, Default)]
pub struct NoProgress;

impl Progress for NoProgress {
    fn begin(&self, _: &str, _: u64) {}
    fn advance(&self, _: u64) {}
    fn end(&self) {}
}
