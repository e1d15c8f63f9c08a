//! Running a tile kernel over every tile of a store: a crossbeam job queue,
//! `threads` workers, at most `in_flight` tiles loaded or waiting at once, and
//! a reorder buffer so the seam policy sees results in tile order.

use super::{PipelineError, Progress};
use crate::store::{PointStore, StoreError};
use crate::tiling::{load_tile, TilePoints};
use crossbeam::channel;
use std::collections::BTreeMap;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

/// Why a kernel could not finish a tile.
#[derive(Debug, thiserror::Error)]
pub enum KernelError {
    /// Some core point depends on points beyond the loaded region: the
    /// pipeline reloads the tile with at least `needed` margin and reruns it.
    #[error("margin too small: {needed} needed")]
    MarginTooSmall { needed: f64 },
    #[error(transparent)]
    Store(#[from] StoreError),
    #[error("{0}")]
    Failed(String),
}

/// A pure function from one tile's points to a tile result.
pub trait TileKernel: Sync {
    type Output: Send;
    /// Stage name shown in progress.
    fn name(&self) -> &str;
    /// Margin to load first; the kernel asks for more when it finds it short.
    fn margin(&self) -> f64;
    fn run(&self, tile: &TilePoints) -> Result<Self::Output, KernelError>;
    /// Whether tiles must carry the store's normals and flags.
    fn needs_normals(&self) -> bool {
        false
    }
}

#[derive(Clone, Copy, Debug)]
pub struct RunOptions {
    pub threads: usize,
    /// Tiles loaded, running or waiting in the reorder buffer at once.
    pub in_flight: usize,
    /// The memory promise global passes plan by (`None`: unbounded, every
    /// pass keeps its state in memory).
    pub budget: Option<super::MemoryBudget>,
}

impl RunOptions {
    /// `threads` workers, no memory promise.
    pub fn new(threads: usize) -> Self {
        let threads = threads.max(1);
        RunOptions {
            threads,
            in_flight: threads + 1,
            budget: None,
        }
    }
}

impl RunOptions {
    /// The same options under the memory promise `budget`.
    pub fn within(self, budget: super::MemoryBudget) -> Self {
        RunOptions {
            budget: Some(budget),
            ..self
        }
    }

    /// Whether a global pass may keep `bytes_per_point` per point in memory
    /// (see [`super::MemoryBudget::holds`]).
    pub fn holds(&self, points: u64, bytes_per_point: u64) -> bool {
        self.budget.is_none_or(|b| b.holds(points, bytes_per_point))
    }
}

#[derive(Clone, Copy, Debug, Default)]
pub struct RunStats {
    pub tiles: usize,
    /// Tiles rerun with a wider margin.
    pub retries: usize,
    pub largest_margin: f64,
}

type TileOutcome<O> = (usize, Result<(O, f64, usize), PipelineError>);

/// Runs `kernel` on every tile; `seam` receives each tile's result in tile
/// order on the calling thread.
pub fn run_tiles<K: TileKernel>(
    store: &PointStore,
    kernel: &K,
    opts: RunOptions,
    progress: &dyn Progress,
    mut seam: impl FnMut(usize, K::Output) -> Result<(), PipelineError>,
) -> Result<RunStats, PipelineError> {
    let n = store.tiles().len();
    let (job_tx, job_rx) = channel::unbounded::<usize>();
    (0..n).for_each(|t| {
        let _ = job_tx.send(t);
    });
    drop(job_tx);
    // A worker takes a token before a job, so tiles are taken in order by
    // token holders and the smallest undelivered tile always holds one.
    let (token_tx, token_rx) = channel::bounded::<()>(opts.in_flight.max(1));
    for _ in 0..opts.in_flight.max(1) {
        let _ = token_tx.send(());
    }
    let (res_tx, res_rx) = channel::unbounded::<TileOutcome<K::Output>>();
    let cancel = AtomicBool::new(false);
    let retries = AtomicUsize::new(0);
    progress.begin(kernel.name(), n as u64);
    let mut stats = RunStats {
        tiles: n,
        ..RunStats::default()
    };
    let result = std::thread::scope(|s| {
        for _ in 0..opts.threads.max(1) {
            let (job_rx, token_rx, res_tx) = (job_rx.clone(), token_rx.clone(), res_tx.clone());
            let (cancel, retries) = (&cancel, &retries);
            s.spawn(move || {
                while token_rx.recv().is_ok() {
                    let Ok(t) = job_rx.recv() else { break };
                    if cancel.load(Ordering::Relaxed) {
                        break;
                    }
                    let out = run_one(store, kernel, t);
                    if let Ok((_, _, r)) = &out {
                        retries.fetch_add(*r, Ordering::Relaxed);
                    }
                    if res_tx.send((t, out)).is_err() {
                        break;
                    }
                }
            });
        }
        drop(res_tx);
        let delivered = deliver(n, &res_rx, &token_tx, progress, &mut seam, &mut stats);
        if delivered.is_err() {
            cancel.store(true, Ordering::Relaxed);
        }
        drop(token_tx);
        delivered
    });
    progress.end();
    stats.retries = retries.load(Ordering::Relaxed);
    result.map(|_| stats)
}

fn deliver<O>(
    n: usize,
    res_rx: &channel::Receiver<TileOutcome<O>>,
    token_tx: &channel::Sender<()>,
    progress: &dyn Progress,
    seam: &mut impl FnMut(usize, O) -> Result<(), PipelineError>,
    stats: &mut RunStats,
) -> Result<(), PipelineError> {
    let mut pending = BTreeMap::new();
    let mut next = 0;
    while next < n {
        let Ok((t, out)) = res_rx.recv() else {
            return Err(PipelineError::WorkerLost);
        };
        pending.insert(t, out?);
        while let Some((out, margin, _)) = pending.remove(&next) {
            stats.largest_margin = stats.largest_margin.max(margin);
            seam(next, out)?;
            progress.advance(1);
            let _ = token_tx.send(());
            next += 1;
        }
    }
    Ok(())
}

/// Loads and runs one tile, widening the margin until the kernel accepts it.
fn run_one<K: TileKernel>(
    store: &PointStore,
    kernel: &K,
    t: usize,
) -> Result<(K::Output, f64, usize), PipelineError> {
    let mut margin = kernel.margin();
    let mut retries = 0;
    loop {
        let tile = load_tile(store, t, margin, kernel.needs_normals())?;
        match kernel.run(&tile) {
            Ok(out) => return Ok((out, margin, retries)),
            Err(KernelError::MarginTooSmall { needed })
                if needed.is_finite() && needed > margin =>
            {
                // Grow geometrically so a tile is loaded O(log) times at most.
                margin = needed.max(margin * 1.5);
                retries += 1;
            }
            Err(KernelError::MarginTooSmall { needed }) => {
                return Err(PipelineError::MarginStuck {
                    tile: t,
                    margin,
                    needed,
                })
            }
            Err(KernelError::Store(e)) => return Err(e.into()),
            Err(KernelError::Failed(reason)) => {
                return Err(PipelineError::Kernel { tile: t, reason })
            }
        }
    }
}
