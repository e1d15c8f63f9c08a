//! The stage contract: what a capability that runs as one pass of tiles
//! over a store declares, as types and associated items (rstar's
//! `RTreeParams` is the model), instead of writing it by hand round a call
//! of [`run_tiles`]: its parameters ([`StageParams`]: `validate`, `cost`),
//! its typed id ([`StageId`]), the store columns its kernel reads and the
//! ones it writes, with the [`Provenance`] it seals them with, its
//! [`TileKernel`], its seam as a type ([`Seam`]: `accept` each tile's
//! result in tile order, `finish` once all are in) and its report.
//! [`run_stage`] runs one: validate, prepare the kernel, create the
//! columns, the tiles through [`run_tiles`] (whose scheduling it leaves as
//! it is), the seam's finish, the report's record in the manifest, the
//! columns sealed.

use super::{run_tiles, KernelCost, PipelineError, RunOptions, RunStats, TileKernel};
use crate::progress::Progress;
use crate::store::{Column, ColumnName, ColumnSpec, PointStore, Provenance, StageId, StoreError};

/// A stage's parameters: plain data that refuses what cannot run and says
/// what a run costs, before any input is read.
pub trait StageParams: std::fmt::Debug {
    /// The stage's error, which a refusal is.
    type Error;
    /// Refuses parameters no run can use, saying which and why.
    fn validate(&self) -> Result<(), Self::Error>;
    /// What a run with these parameters costs, for the memory and disk
    /// plans (`RunSettings::open`, `info --plan`).
    fn cost(&self) -> KernelCost;
}

/// A capability's pass of tiles over a store, declared.
pub trait Stage {
    /// The stage's id: its kernel's name ([`TileKernel::name`] is
    /// `ID.name()`), the progress label, the directory of its saved tiles.
    const ID: StageId;
    /// The store columns its kernel reads ([`TileKernel::reads`]), loaded
    /// into every tile; the stage's preparation makes them when the store
    /// lacks them.
    const READS: &'static [ColumnSpec];
    /// The store columns it writes: created before its tiles, handed to its
    /// seam ([`StageColumns`]), sealed with [`Stage::provenance`] once the
    /// seam has finished.
    const WRITES: &'static [ColumnSpec];
    /// Its parameters.
    type Params: StageParams;
    /// Its tile kernel.
    type Kernel: TileKernel;
    /// Its seam, over the store and the columns it writes.
    type Seam<'s>: Seam<
        Tile = <Self::Kernel as TileKernel>::Output,
        Report = Self::Report,
        Error = Self::Error,
    >
    where
        Self: 's;
    /// What a run reports.
    type Report;
    /// Its errors: its parameters' refusals, the store's and the
    /// pipeline's among them.
    type Error: From<<Self::Params as StageParams>::Error> + From<PipelineError> + From<StoreError>;

    /// The parameters it runs with.
    fn params(&self) -> &Self::Params;

    /// What a run costs (its parameters' [`StageParams::cost`]).
    fn cost(&self) -> KernelCost {
        self.params().cost()
    }

    /// What the columns it writes record as their making, so a later pass
    /// reuses them only when it would make the same ones.
    fn provenance(&self) -> Provenance;

    /// The kernel for `store`, after whatever the kernel needs of the store
    /// is there (its spacing, the columns it reads, computed when absent).
    fn kernel(
        &self,
        store: &mut PointStore,
        opts: RunOptions,
        progress: &dyn Progress,
    ) -> Result<Self::Kernel, Self::Error>;

    /// What the store's manifest keeps of a finished run's report, recorded
    /// before the columns are sealed (none by default; the normals' sampling
    /// statistics).
    fn record(&self, store: &mut PointStore, report: &Self::Report) -> Result<(), Self::Error> {
        let _ = (store, report);
        Ok(())
    }

    /// The seam of a run of `kernel` over `store`, writing `columns`.
    fn seam<'s>(
        &'s self,
        store: &'s PointStore,
        kernel: &Self::Kernel,
        columns: &'s StageColumns,
    ) -> Result<Self::Seam<'s>, Self::Error>;
}

/// Where a stage's tile results go: each tile's in tile order, then the
/// global part once all are in.
pub trait Seam {
    /// One tile's result, as the kernel gives it.
    type Tile;
    /// What the stage reports.
    type Report;
    /// The stage's error.
    type Error;
    /// Takes the result of tile `tile` (0-based); called in tile order on
    /// the thread that runs the stage.
    fn accept(&mut self, tile: usize, out: Self::Tile) -> Result<(), PipelineError>;
    /// Every tile is in (`run` says how they ran): the global part of the
    /// stage, under the run's options (its threads, its memory plan), and
    /// its report.
    fn finish(
        self,
        run: RunStats,
        opts: RunOptions,
        progress: &dyn Progress,
    ) -> Result<Self::Report, Self::Error>;
}

/// The columns a stage writes ([`Stage::WRITES`]), made for its run.
pub struct StageColumns {
    columns: Vec<(ColumnSpec, Column)>,
}

impl StageColumns {
    /// Creates (or empties to remake) each of `specs` in `store`.
    fn create(store: &mut PointStore, specs: &[ColumnSpec]) -> Result<Self, StoreError> {
        let columns = specs
            .iter()
            .map(|s| Ok((*s, store.create_column(s)?)))
            .collect::<Result<_, StoreError>>()?;
        Ok(StageColumns { columns })
    }

    /// The column `spec`; a stage asking for one it does not write gets
    /// the store's error for a missing column.
    pub fn get(&self, spec: &ColumnSpec) -> Result<&Column, StoreError> {
        self.columns
            .iter()
            .find(|(s, _)| s == spec)
            .map(|(_, c)| c)
            .ok_or(StoreError::MissingColumn {
                column: ColumnName::Computed(spec.name),
            })
    }

    /// Seals every column in `store`, in the order the stage declared them.
    fn seal(self, store: &mut PointStore, made_by: Provenance) -> Result<(), StoreError> {
        for (spec, column) in &self.columns {
            store.finish_column(spec, column, made_by.clone())?;
        }
        Ok(())
    }
}

/// Runs `stage` over every tile of `store`: its parameters validated, its
/// kernel prepared, the columns it writes created, the tiles run by
/// [`run_tiles`] with each result handed to its seam in tile order, the
/// seam finished, what the manifest keeps of its report recorded
/// ([`Stage::record`]), the columns sealed with its provenance. In a tile job
/// the result is [`PipelineError::Stopped`], as [`run_tiles`]'s is.
pub fn run_stage<S: Stage>(
    store: &mut PointStore,
    stage: &S,
    opts: RunOptions,
    progress: &dyn Progress,
) -> Result<S::Report, S::Error> {
    stage.params().validate()?;
    let kernel = stage.kernel(store, opts, progress)?;
    debug_assert_eq!(kernel.name(), S::ID.name());
    debug_assert_eq!(kernel.reads(), S::READS);
    let columns = StageColumns::create(store, S::WRITES)?;
    let report = {
        let store = &*store;
        let mut seam = stage.seam(store, &kernel, &columns)?;
        let run = run_tiles(store, &kernel, opts, progress, |t, out| seam.accept(t, out))?;
        seam.finish(run, opts, progress)?
    };
    stage.record(store, &report)?;
    columns.seal(store, stage.provenance())?;
    Ok(report)
}
