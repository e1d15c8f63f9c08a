//! This process's part of a run kept in a run directory: its job (all of
//! the run, up to a stage, or some tiles of one), the store it works on
//! (ingested into the run directory first when the run has none yet), the
//! checkpoints its tile stages keep their tiles in, which say after the
//! run where the job stopped and which tile files were found damaged, and
//! the log lines that say what the job did (`status` reads them back:
//! `processes`), and a global stage's result kept for a resumed run
//! ([`Session::kept_or`]).

use super::{ProcessRecord, RunDir, RunDirError};
use crate::pipeline::{KernelCost, Prepared, Progress, RunSettings, WorkspaceError};
use crate::store::{ingest_kept, is_store, Checkpoints, Job, PointStore, StageId, Workspace};
use serde::{de::DeserializeOwned, Serialize};
use std::fmt::Display;
use std::path::{Path, PathBuf};

/// A process's job in a run directory.
#[derive(Clone, Debug)]
pub struct Session {
    run: RunDir,
    /// Shared by the clones, and by the store that keeps tiles in them:
    /// the job learns where it stopped from them, not from an error chain.
    checkpoints: Checkpoints,
}

impl Session {
    /// The job `job` in `run`.
    pub fn new(run: RunDir, job: Job) -> Self {
        let checkpoints = Checkpoints::new(run.tiles_dir(), job);
        Session { run, checkpoints }
    }

    /// The run directory.
    pub fn run(&self) -> &RunDir {
        &self.run
    }

    /// The result of the global stage `stage`: the one this run kept, while
    /// `valid` says what it left in the store is still there (a resumed
    /// run), else `compute`'s, kept for the next resume.
    pub fn kept_or<T, E>(
        session: Option<&Self>,
        stage: StageId,
        valid: bool,
        compute: impl FnOnce() -> Result<T, E>,
    ) -> Result<T, E>
    where
        T: Serialize + DeserializeOwned,
        E: From<RunDirError>,
    {
        let kept = match session {
            Some(s) => s.run.stage::<T>(stage)?,
            None => None,
        };
        match kept {
            Some(result) if valid => Ok(result),
            _ => {
                let result = compute()?;
                if let Some(s) = session {
                    s.run.keep_stage(stage, &result)?;
                }
                Ok(result)
            }
        }
    }

    /// What this process does of the run.
    pub fn job(&self) -> &Job {
        &self.checkpoints.job
    }

    /// The stage where the job stopped as asked (`--until`, a tile job),
    /// if it did.
    pub fn stopped_at(&self) -> Option<&str> {
        self.checkpoints.stopped_at()
    }

    /// The tile files the job found damaged (removed, their tiles
    /// recomputed).
    pub fn damaged_tiles(&self) -> Vec<PathBuf> {
        self.checkpoints.damaged()
    }

    /// The run's store (`input` itself when it is one, else the run
    /// directory's, ingested first when the run has none yet), keeping
    /// finished tiles for this job, with its plan and run options; and the
    /// scratch entries killed runs left that were removed on the way.
    pub fn open(
        &self,
        settings: &RunSettings,
        input: &Path,
        output: &Path,
        cost: KernelCost,
        progress: &dyn Progress,
    ) -> Result<(Prepared, Vec<PathBuf>), RunDirError> {
        settings.check_floor(&cost)?;
        settings.check_selection(input)?;
        let tile_job = matches!(self.job(), Job::Tiles { .. });
        let store_dir = match is_store(input) {
            true => input.to_path_buf(),
            false => self.run.store_dir(),
        };
        // The run's store appears whole (renamed into place) or not at all:
        // one there without its manifest was damaged, not left half-built.
        if store_dir.exists() && !is_store(&store_dir) {
            self.run.check_store()?;
        }
        let mut reclaimed = Vec::new();
        if !is_store(&store_dir) {
            if tile_job {
                return Err(RunDirError::NoStoreYet {
                    dir: self.run.dir().to_path_buf(),
                });
            }
            reclaimed = self.ingest(settings, input, &store_dir, output, cost, progress)?;
        }
        // Tile jobs of one stage run side by side and only read the store.
        let mut store = match tile_job {
            true => PointStore::open_shared(&store_dir)?,
            false => PointStore::open(&store_dir)?,
        };
        if *self.job() == Job::Whole {
            self.checkpoints.remove_leftovers()?;
        }
        store.keep_tiles(self.checkpoints.clone());
        Ok((settings.prepare(Workspace::kept(store), cost)?, reclaimed))
    }

    /// Builds the run's store from `input` at `store_dir`, the run
    /// directory its scratch place; returns what killed runs left there.
    fn ingest(
        &self,
        settings: &RunSettings,
        input: &Path,
        store_dir: &Path,
        output: &Path,
        cost: KernelCost,
        progress: &dyn Progress,
    ) -> Result<Vec<PathBuf>, RunDirError> {
        let in_run = RunSettings {
            scratch_dir: Some(self.run.dir().to_path_buf()),
            ..settings.clone()
        };
        let (_, reclaimed) = in_run.check_places(input, output, &cost.in_run_dir())?;
        let build = settings.build_options(cost);
        ingest_kept(input, store_dir, &build, settings.read.clone(), progress).map_err(
            |source| WorkspaceError::Reading {
                path: input.to_path_buf(),
                source,
            },
        )?;
        Ok(reclaimed)
    }

    /// Starts the job `job` in `run`: logged, and recorded as this
    /// process's (the record, removed when dropped, tells `status` this
    /// process apart from a dead one).
    pub fn start(run: RunDir, job: Job) -> (Self, ProcessRecord) {
        let record = ProcessRecord::record(run.dir());
        let session = Session::new(run, job);
        session.log_start();
        (session, record)
    }

    /// Logs how the job ended, and returns how the caller's run ends:
    /// stopped as asked (its error, because it did, is then no failure),
    /// done (the `output` and its `summary` recorded), or failed.
    pub fn finish<E>(
        &self,
        outcome: Result<(), E>,
        output: &Path,
        summary: Option<String>,
    ) -> Result<(), E>
    where
        E: Display + From<RunDirError>,
    {
        match outcome {
            Err(_) if self.log_stopped() => Ok(()),
            Ok(()) => Ok(self.log_done(output, summary)?),
            Err(e) => {
                self.log_failed(&e);
                Err(e)
            }
        }
    }

    /// Logs that the job starts.
    pub fn log_start(&self) {
        self.run.log(&format!("start {}", job_text(self.job())));
    }

    /// Logs each tile file the job found damaged (removed, its tile
    /// recomputed); returns the lines, for the caller to show too.
    pub fn log_damaged_tiles(&self) -> Vec<String> {
        let lines: Vec<String> = self
            .damaged_tiles()
            .iter()
            .map(|tile| {
                format!(
                    "damaged tile file {} removed, its tile recomputed",
                    tile.display()
                )
            })
            .collect();
        lines.iter().for_each(|line| self.run.log(line));
        lines
    }

    /// Whether the job stopped as asked (its run ended in an error
    /// because it did): then logged as done.
    pub fn log_stopped(&self) -> bool {
        let Some(stage) = self.stopped_at() else {
            return false;
        };
        let what = job_text(self.job());
        self.run.log(&format!(
            "done {what} (stopped at {stage}), peak {}",
            peak()
        ));
        true
    }

    /// Records that the job ran to its end: a whole run (or an `--until`
    /// job that found no stage to stop at, so ran it all) wrote `output`,
    /// with its `summary`. A tile job that did not stop never met its stage:
    /// an error, logged as its failure; one that did wrote no output.
    pub fn log_done(&self, output: &Path, summary: Option<String>) -> Result<(), RunDirError> {
        if let (Job::Tiles { stage, .. }, None) = (self.job(), self.stopped_at()) {
            let err = RunDirError::NoSuchTileStage {
                stage: stage.clone(),
                dir: self.run.dir().to_path_buf(),
            };
            self.log_failed(&err);
            return Err(err);
        }
        if !matches!(self.job(), Job::Tiles { .. }) {
            self.run.finish(output, summary)?;
        }
        let what = job_text(self.job());
        self.run.log(&format!("done {what}, peak {}", peak()));
        Ok(())
    }

    /// Logs that the job failed, and why (the error's `{:#}`: an error
    /// chain's causes on one line).
    pub fn log_failed(&self, err: &dyn Display) {
        let what = job_text(self.job());
        self.run.log(&format!("failed {what}: {err:#}"));
    }
}

/// The store a run works on, with its plan and run options: in the run
/// directory when `session` keeps one ([`Session::open`]), else `input`
/// itself when it is a store or a scratch store beside `output` built from
/// it ([`RunSettings::open`]); and the scratch entries killed runs left
/// that were removed on the way.
pub fn open_input(
    settings: &RunSettings,
    session: Option<&Session>,
    input: &Path,
    output: &Path,
    cost: KernelCost,
    progress: &dyn Progress,
) -> Result<(Prepared, Vec<PathBuf>), RunDirError> {
    match session {
        Some(session) => session.open(settings, input, output, cost, progress),
        None => Ok(settings.open(input, output, cost, progress)?),
    }
}

/// A job in words, for the log: `run`, `job --until STAGE`, `job --stage
/// STAGE --share I/N`.
fn job_text(job: &Job) -> String {
    match job {
        Job::Whole => "run".to_string(),
        Job::Until(s) => format!("job --until {s}"),
        Job::Tiles { stage, tiles } => format!("job --stage {stage} {tiles}"),
    }
}

/// This process's peak memory so far, for the log.
fn peak() -> String {
    crate::memory::peak_rss_bytes().map_or("?".into(), crate::units::human_bytes)
}
