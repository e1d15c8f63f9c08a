//! Running a tile kernel over every tile of a store: a crossbeam job queue,
//! `threads` workers, at most `in_flight` tiles loaded or waiting at once, and
//! a reorder buffer so the seam policy sees results in tile order. In a
//! resumable run the store keeps finished tiles ([`crate::store::Checkpoints`]):
//! a kernel with a [`Codec`] has each result saved as it finishes and read
//! back instead of recomputed, and a tile job computes some tiles only.

use super::shares::{Shares, Taken};
use super::{Codec, KernelError, PipelineError, RunOptions, TileKernel};
use crate::progress::Progress;
use crate::store::{Checkpoints, Job, PointStore};
use crate::tiling::{count_loaded, load_tile};
use crossbeam::channel;
use std::collections::BTreeMap;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

/// What a run of tiles did.
#[derive(Clone, Copy, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct RunStats {
    /// Tiles processed.
    pub tiles: usize,
    /// Tiles rerun with a wider margin.
    pub retries: usize,
    /// The widest margin any tile was finally run with, in the store's coordinate units.
    pub largest_margin: f64,
    /// Tiles read back from a resumable run's saved results.
    pub reused: usize,
}

type TileOutcome<O> = (usize, Result<(O, f64, usize), PipelineError>);

/// Runs `kernel` on every tile; `seam` receives each tile's result in tile
/// order on the calling thread. In a tile job (see [`Job`]) only the job's
/// tiles are computed and saved, `seam` sees nothing, and the result is
/// [`PipelineError::Stopped`].
pub fn run_tiles<K: TileKernel>(
    store: &PointStore,
    kernel: &K,
    opts: RunOptions,
    progress: &dyn Progress,
    mut seam: impl FnMut(usize, K::Output) -> Result<(), PipelineError>,
) -> Result<RunStats, PipelineError> {
    let n = store.tiles().len();
    let keep = store
        .checkpoints()
        .and_then(|c| kernel.codec().map(|k| (c, k)));
    let work = Work::for_job(store.checkpoints(), kernel.name(), n, keep.is_some()).map_err(
        |e| match e {
            PipelineError::Stopped { stage } => stop(store, stage),
            e => e,
        },
    )?;
    let (reused, stage) = resumed(keep.as_ref().map(|(c, _)| *c), kernel.name(), &work.tiles);
    let tiles = &work.tiles;
    let (job_tx, job_rx) = channel::unbounded::<usize>();
    (0..tiles.len()).for_each(|i| {
        let _ = job_tx.send(i);
    });
    drop(job_tx);
    // A worker takes a token before a job, so jobs are taken in order by
    // token holders and the smallest undelivered job always holds one.
    let (token_tx, token_rx) = channel::bounded::<()>(opts.in_flight.max(1));
    for _ in 0..opts.in_flight.max(1) {
        let _ = token_tx.send(());
    }
    let (res_tx, res_rx) = channel::unbounded::<TileOutcome<K::Output>>();
    let cancel = AtomicBool::new(false);
    let retries = AtomicUsize::new(0);
    let shares = opts
        .tile_bytes
        .map(|b| Shares::new(b, opts.tile_room.unwrap_or(b * opts.in_flight as u64)));
    let shares = shares.as_ref();
    progress.begin(&stage, tiles.len() as u64);
    let mut stats = RunStats {
        tiles: n,
        reused,
        ..RunStats::default()
    };
    let keep = keep.as_ref().map(|(c, k)| (*c, k));
    let result = std::thread::scope(|s| {
        for _ in 0..opts.threads.max(1) {
            let (job_rx, token_rx, res_tx) = (job_rx.clone(), token_rx.clone(), res_tx.clone());
            let (cancel, retries) = (&cancel, &retries);
            s.spawn(move || {
                while token_rx.recv().is_ok() {
                    let Ok(i) = job_rx.recv() else { break };
                    if cancel.load(Ordering::Relaxed) {
                        break;
                    }
                    let out = fetch(store, kernel, keep, shares, tiles[i]);
                    if let Ok((_, _, r)) = &out {
                        retries.fetch_add(*r, Ordering::Relaxed);
                    }
                    if res_tx.send((i, out)).is_err() {
                        break;
                    }
                }
            });
        }
        drop(res_tx);
        let delivered = deliver(
            tiles.len(),
            &res_rx,
            &token_tx,
            progress,
            &mut stats,
            |i, out| {
                if work.to_seam {
                    seam(tiles[i], out)
                } else {
                    Ok(())
                }
            },
        );
        if delivered.is_err() {
            cancel.store(true, Ordering::Relaxed);
        }
        drop(token_tx);
        delivered
    });
    progress.end();
    stats.retries = retries.load(Ordering::Relaxed);
    result?;
    if work.to_seam {
        Ok(stats)
    } else {
        Err(stop(store, kernel.name()))
    }
}

/// The job is done at `stage`: says so to whoever holds the checkpoints.
fn stop(store: &PointStore, stage: &'static str) -> PipelineError {
    if let Some(c) = store.checkpoints() {
        c.stop_at(stage);
    }
    PipelineError::Stopped { stage }
}

/// How many of `tiles` a resumed run reads back, and the stage's name as
/// progress shows it ("normals (resumed: 812 of 1024 tiles reused)").
fn resumed(keep: Option<&Checkpoints>, name: &str, tiles: &[usize]) -> (usize, String) {
    let reused = keep.map_or(0, |c| tiles.iter().filter(|&&t| c.has(name, t)).count());
    let label = match reused {
        0 => name.to_string(),
        r => format!("{name} (resumed: {r} of {} tiles reused)", tiles.len()),
    };
    (reused, label)
}

/// The tiles a run of one stage handles, and whether the seam sees them.
struct Work {
    tiles: Vec<usize>,
    to_seam: bool,
}

impl Work {
    /// What this process does of stage `stage` (`n` tiles) for its job.
    fn for_job(
        checkpoints: Option<&Checkpoints>,
        stage: &'static str,
        n: usize,
        kept: bool,
    ) -> Result<Work, PipelineError> {
        let all = Work {
            tiles: (0..n).collect(),
            to_seam: true,
        };
        let Some(c) = checkpoints else {
            return Ok(all);
        };
        let this = |s: &str| Checkpoints::slug(s) == Checkpoints::slug(stage);
        match &c.job {
            Job::Whole => Ok(all),
            Job::Until(s) if this(s) => Err(PipelineError::Stopped { stage }),
            Job::Until(_) => Ok(all),
            Job::Tiles { stage: s, tiles } if this(s) => match kept {
                true => Ok(Work {
                    tiles: tiles.tiles(n).filter(|&t| !c.has(stage, t)).collect(),
                    to_seam: false,
                }),
                false => Err(PipelineError::NotSplittable { stage }),
            },
            // A tile job of a later stage replays this one, complete.
            Job::Tiles { .. } => match c.count(stage, n) {
                done if kept && done == n => Ok(all),
                done => Err(PipelineError::StageIncomplete {
                    stage,
                    done: if kept { done } else { 0 },
                    total: n,
                }),
            },
        }
    }
}

/// A tile's result: read back when saved, else computed (and saved).
fn fetch<K: TileKernel>(
    store: &PointStore,
    kernel: &K,
    keep: Option<(&Checkpoints, &Codec<K::Output>)>,
    shares: Option<&Shares>,
    t: usize,
) -> Result<(K::Output, f64, usize), PipelineError> {
    let Some((c, codec)) = keep else {
        return run_one(store, kernel, shares, t);
    };
    if let Some(bytes) = c.load(kernel.name(), t)? {
        // One that does not decode or fit its tile (checksum right,
        // content not) is recomputed like a damaged one.
        match (codec.decode)(&bytes) {
            Ok(out) if (codec.fits)(&out, &store.tiles()[t], store.len()) => {
                return Ok((out, kernel.margin(), 0));
            }
            _ => c.reject(kernel.name(), t)?,
        }
    }
    let (out, margin, retries) = run_one(store, kernel, shares, t)?;
    let bytes = (codec.encode)(&out).map_err(|e| PipelineError::Codec {
        stage: kernel.name(),
        tile: t,
        source: Box::new(e),
    })?;
    c.save(kernel.name(), t, &bytes)?;
    Ok((out, margin, retries))
}

fn deliver<O>(
    n: usize,
    res_rx: &channel::Receiver<TileOutcome<O>>,
    token_tx: &channel::Sender<()>,
    progress: &dyn Progress,
    stats: &mut RunStats,
    mut seam: impl FnMut(usize, O) -> Result<(), PipelineError>,
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
    shares: Option<&Shares>,
    t: usize,
) -> Result<(K::Output, f64, usize), PipelineError> {
    let mut margin = kernel.margin();
    let mut retries = 0;
    // The points and bytes the tile at this margin was found to need.
    let mut known: Option<(u64, u64)> = None;
    loop {
        let mut memory = match shares {
            Some(s) => take_before_load(store, kernel, s, t, margin, known)?,
            None => None,
        };
        let tile = load_tile(store, t, margin, kernel.reads())?;
        if let (Some(s), Some(taken), Some(need)) = (shares, &mut memory, kernel.bytes_for(&tile)) {
            if need > s.room() {
                return Err(over_budget(s, t, margin, tile.points.len() as u64, need));
            }
            if !taken.try_grow_to(need) {
                // Give back the points and the bytes, then wait for the
                // whole need holding nothing: no worker waits holding memory.
                known = Some((tile.points.len() as u64, need));
                continue;
            }
        }
        match kernel.run(&tile) {
            Ok(out) => return Ok((out, margin, retries)),
            Err(KernelError::MarginTooSmall { needed })
                if needed.is_finite() && needed > margin =>
            {
                // Grow geometrically so a tile is loaded O(log) times at most.
                margin = needed.max(margin * 1.5);
                retries += 1;
                known = None;
            }
            Err(KernelError::MarginTooSmall { needed }) => {
                return Err(PipelineError::MarginStuck {
                    tile: t,
                    margin,
                    needed,
                })
            }
            Err(KernelError::Store(e)) => return Err(e.into()),
            Err(KernelError::Failed(fault)) => {
                return Err(PipelineError::Kernel {
                    tile: t,
                    source: Box::new(fault),
                })
            }
            Err(KernelError::Source(source)) => {
                return Err(PipelineError::Kernel { tile: t, source })
            }
        }
    }
}

/// Takes the room a tile needs before it is loaded: what it was found to
/// need (`known`: its points and bytes), else what its counted points
/// hold loaded. `None` for a
/// kernel whose tiles keep to the plan's sizes.
fn take_before_load<'s, K: TileKernel>(
    store: &PointStore,
    kernel: &K,
    shares: &'s Shares,
    t: usize,
    margin: f64,
    known: Option<(u64, u64)>,
) -> Result<Option<Taken<'s>>, PipelineError> {
    if kernel.bytes_to_load(0).is_none() {
        return Ok(None);
    }
    let (points, bytes) = match known {
        Some(known) => known,
        None => {
            let points = count_loaded(store, t, margin)?;
            (points, kernel.bytes_to_load(points).unwrap_or(0))
        }
    };
    shares
        .take(bytes)
        .map(Some)
        .ok_or_else(|| over_budget(shares, t, margin, points, bytes))
}

fn over_budget(
    shares: &Shares,
    tile: usize,
    margin: f64,
    points: u64,
    bytes: u64,
) -> PipelineError {
    PipelineError::OverBudget {
        tile,
        margin,
        points: points as usize,
        need_mib: bytes.div_ceil(1 << 20),
        room_mib: shares.room() >> 20,
    }
}
