//! A run over a point cloud as the command line runs it, for a library
//! caller too: the store opened within the memory plan (the run
//! directory's, when the run keeps one; [`PointRun::open`], for a run that
//! writes a mesh, lines or lists), and end to end the shell the per-point
//! stages (normals, curvature, outliers) share ([`PointRun::run`]): the
//! stage computes its columns on the store, and the rows are written in
//! input order. What the run has to say on the way reaches the caller as
//! [`Said`].

use super::{open_input, RunDirError, Session};
use crate::io::{place, IoError};
use crate::pipeline::{KernelCost, Prepared, Progress, RunOptions, RunSettings};
use crate::store::{Kept, PointStore, Rows};
use std::path::{Path, PathBuf};

/// Where a run works and who hears it.
pub struct PointRun<'a> {
    /// The memory promise, threads, how the input is read, the scratch.
    pub settings: &'a RunSettings,
    /// This process's part of the run in its directory, if it keeps one.
    pub session: Option<&'a Session>,
    /// Write the points the selection leaves out too (flagged).
    pub keep_unselected: bool,
    /// Progress bars, or none.
    pub progress: &'a dyn Progress,
    /// Hears what the run says on the way.
    pub hear: &'a dyn Hear,
}

/// Who hears what a run says on the way (the CLI prints it and keeps it
/// for `--report`).
pub trait Hear {
    /// `said`, as the run says it.
    fn hear(&self, said: Said<'_>);
}

/// What a run says on the way.
pub enum Said<'a> {
    /// Files killed runs left, removed before this one began.
    Reclaimed(&'a [PathBuf]),
    /// The store the run works on, opened (its manifest says what of the
    /// input it lacks).
    Opened(&'a PointStore),
    /// A note for the user (what the output format cannot hold).
    Note(String),
}

/// What a per-point stage's computation is given beside the store.
pub struct Computing<'a> {
    /// Run options whose tiles in flight fit the memory plan.
    pub opts: RunOptions,
    /// Progress bars, or none.
    pub progress: &'a dyn Progress,
    /// The run directory's job, if the run keeps one.
    pub session: Option<&'a Session>,
}

impl PointRun<'_> {
    /// The store for a run that writes no row per point (a mesh, lines,
    /// lists): `input` itself when it is one, else a scratch store beside
    /// `output` built from the input file, or the run directory's, keeping
    /// `kept` of the input (the exact coordinates for a mesh whose
    /// vertices are input points, else nothing: the attributes and LAS
    /// records only an export of every point reads); its memory plan, and
    /// run options that keep the tiles in flight within it, for a kernel
    /// that costs `cost`.
    pub fn open(
        &self,
        (input, output): (&Path, &Path),
        cost: KernelCost,
        kept: Kept,
    ) -> Result<Prepared, RunDirError> {
        let settings = RunSettings {
            keep: kept,
            ..self.settings.clone()
        };
        self.open_with(&settings, input, output, cost)
    }

    /// [`PointRun::open`] in `settings`.
    fn open_with(
        &self,
        settings: &RunSettings,
        input: &Path,
        output: &Path,
        cost: KernelCost,
    ) -> Result<Prepared, RunDirError> {
        let (opened, reclaimed) =
            open_input(settings, self.session, input, output, cost, self.progress)?;
        self.hear.hear(Said::Reclaimed(&reclaimed));
        self.hear.hear(Said::Opened(&opened.ws.store));
        Ok(opened)
    }

    /// The cost of a per-point run of a stage whose kernel costs `cost`:
    /// its export frees the scratch store's positions before the output
    /// grows ([`Self::run`]), which the disk plan counts.
    pub fn cost(cost: KernelCost) -> KernelCost {
        KernelCost {
            export_frees_positions: true,
            ..cost
        }
    }

    /// Runs a stage whose kernel costs `cost` from `input` to `output`:
    /// `compute` on the opened store, then `write` of its rows (it may say
    /// a note to the run's hearer). Returns the computation's report and
    /// what the writer returned. `E` is any error the run's own convert
    /// into (the CLI's `anyhow::Error`, a caller's boxed error).
    pub fn run<R, W, E>(
        &self,
        (input, output): (&Path, &Path),
        cost: KernelCost,
        compute: impl FnOnce(&mut PointStore, Computing<'_>) -> Result<R, E>,
        write: impl FnOnce(&PointStore, &Rows<'_>, &dyn Hear) -> Result<W, E>,
    ) -> Result<(R, W), E>
    where
        E: From<RunDirError> + From<IoError>,
    {
        place::check_distinct(input, output)?;
        // The export reads the input's points again (`Rows::input`).
        let settings = RunSettings {
            keep: Kept::Nothing,
            ..self.settings.clone()
        };
        let mut opened = self.open_with(&settings, input, output, Self::cost(cost))?;
        let store = &mut opened.ws.store;
        let (progress, session) = (self.progress, self.session);
        let report = compute(
            store,
            Computing {
                opts: opened.opts,
                progress,
                session,
            },
        )?;
        // The export reads no position: a scratch store frees them.
        store.release_positions().map_err(RunDirError::from)?;
        let rows = Rows {
            output,
            window: opened.plan.window_points,
            input: Some((input, &self.settings.read)),
            keep_unselected: self.keep_unselected,
            progress,
        };
        Ok((report, write(store, &rows, self.hear)?))
    }
}
