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
    let id = S::ID.name();
    let refuse = |what| Err(PipelineError::KernelNotTheStages { stage: id, what });
    if kernel.name() != id {
        refuse("calls itself by another name")?;
    }
    if kernel.reads() != S::READS {
        refuse("reads other columns than the stage declares")?;
    }
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pipeline::KernelError;
    use crate::progress::NoProgress;
    use crate::store::{Item, StageId};
    use crate::tiling::TilePoints;
    use glam::DVec3;

    const MARK: ColumnSpec = ColumnSpec::new("mark.u8", Item::U8);

    /// Refused when `fail` is set.
    #[derive(Debug)]
    struct Params {
        fail: bool,
        fail_finish: bool,
        /// The kernel calls itself by another name than the stage's id.
        misnamed: bool,
    }

    #[derive(Debug, thiserror::Error)]
    #[error("refused")]
    struct Refused;

    impl StageParams for Params {
        type Error = PipelineError;
        fn validate(&self) -> Result<(), PipelineError> {
            match self.fail {
                true => Err(PipelineError::seam(Refused)),
                false => Ok(()),
            }
        }
        fn cost(&self) -> KernelCost {
            KernelCost {
                bytes_per_point: 64,
                global_per_point: 0,
                contracts_boundaries: false,
                resident_per_point: 0.0,
                window_bytes_per_point: 0,
                scratch_per_point: 1,
                export_scratch_per_point: 1,
                checkpoint_per_point: 0,
                external_scratch_saving: 0,
                export_frees_positions: false,
                output_per_point: 0,
                beside_output_per_point: 0,
                parallel_in_tile: false,
                margin_spacings: 0.0,
                resident_bytes: 0,
            }
        }
    }

    /// Each tile's core points, under the name it is given.
    struct Count(&'static str);

    impl TileKernel for Count {
        type Output = u64;
        fn name(&self) -> &'static str {
            self.0
        }
        fn margin(&self) -> f64 {
            0.0
        }
        fn run(&self, tile: &TilePoints) -> Result<u64, KernelError> {
            Ok(tile.n_core as u64)
        }
    }

    /// Marks every point with its tile's number; reports the tiles in the
    /// order the seam took them and the points they held.
    struct Marks(Params);

    struct MarkSeam<'s> {
        store: &'s PointStore,
        column: &'s Column,
        seen: Vec<(usize, u64)>,
        fail: bool,
    }

    impl Seam for MarkSeam<'_> {
        type Tile = u64;
        type Report = Vec<(usize, u64)>;
        type Error = PipelineError;
        fn accept(&mut self, tile: usize, out: u64) -> Result<(), PipelineError> {
            let start = self.store.tiles()[tile].start;
            self.column
                .write_bytes(start, &vec![tile as u8; out as usize])?;
            self.seen.push((tile, out));
            Ok(())
        }
        fn finish(
            self,
            _: RunStats,
            _: RunOptions,
            _: &dyn Progress,
        ) -> Result<Self::Report, PipelineError> {
            match self.fail {
                true => Err(PipelineError::seam(Refused)),
                false => Ok(self.seen),
            }
        }
    }

    impl Stage for Marks {
        const ID: StageId = StageId::new("marks");
        const READS: &'static [ColumnSpec] = &[];
        const WRITES: &'static [ColumnSpec] = &[MARK];
        type Params = Params;
        type Kernel = Count;
        type Seam<'s> = MarkSeam<'s>;
        type Report = Vec<(usize, u64)>;
        type Error = PipelineError;
        fn params(&self) -> &Params {
            &self.0
        }
        fn provenance(&self) -> Provenance {
            Provenance::of("marks", &self.0)
        }
        fn kernel(
            &self,
            _: &mut PointStore,
            _: RunOptions,
            _: &dyn Progress,
        ) -> Result<Count, PipelineError> {
            Ok(Count(match self.0.misnamed {
                true => "not marks",
                false => Marks::ID.name(),
            }))
        }
        fn seam<'s>(
            &'s self,
            store: &'s PointStore,
            _: &Count,
            columns: &'s StageColumns,
        ) -> Result<MarkSeam<'s>, PipelineError> {
            Ok(MarkSeam {
                store,
                column: columns.get(&MARK)?,
                seen: Vec::new(),
                fail: self.0.fail_finish,
            })
        }
    }

    fn store(dir: &std::path::Path) -> PointStore {
        let pts: Vec<DVec3> = (0..3000)
            .map(|i| DVec3::new(i as f64 * 0.01, (i % 5) as f64 * 0.01, 0.0))
            .collect();
        crate::store::test_store::store_of(pts, 400, dir)
    }

    fn marks(fail: bool, fail_finish: bool) -> Marks {
        Marks(Params {
            fail,
            fail_finish,
            misnamed: false,
        })
    }

    #[test]
    fn the_seam_takes_every_tile_in_order_and_the_columns_are_sealed() {
        let dir = tempfile::tempdir().expect("tempdir");
        let mut store = store(dir.path());
        let stage = marks(false, false);
        let seen = run_stage(&mut store, &stage, RunOptions::new(2), &NoProgress).expect("run");
        let tiles = store.tiles().to_vec();
        assert!(tiles.len() > 1);
        let order: Vec<usize> = seen.iter().map(|s| s.0).collect();
        assert_eq!(order, (0..tiles.len()).collect::<Vec<_>>());
        assert!(seen.iter().zip(&tiles).all(|(s, t)| s.1 == t.count));
        assert_eq!(store.provenance(&MARK), Some(&stage.provenance()));
        let column = Column::open(&store.dir().join(MARK.name), 1, false).expect("open");
        let mut bytes = Vec::new();
        column
            .read_u8(tiles[1].start, tiles[1].count, &mut bytes)
            .expect("read");
        assert!(bytes.iter().all(|&b| b == 1));
    }

    #[test]
    fn refused_parameters_touch_nothing() {
        let dir = tempfile::tempdir().expect("tempdir");
        let mut store = store(dir.path());
        let err = run_stage(
            &mut store,
            &marks(true, false),
            RunOptions::new(1),
            &NoProgress,
        );
        assert!(matches!(err, Err(PipelineError::Seam(_))));
        assert!(!store.has_column(&MARK));
    }

    #[test]
    fn a_failed_finish_leaves_the_columns_unsealed() {
        let dir = tempfile::tempdir().expect("tempdir");
        let mut store = store(dir.path());
        let err = run_stage(
            &mut store,
            &marks(false, true),
            RunOptions::new(1),
            &NoProgress,
        );
        assert!(err.is_err());
        assert!(store.has_column(&MARK));
        assert_eq!(store.provenance(&MARK), None);
    }

    #[test]
    fn a_kernel_that_is_not_the_stages_is_refused_before_any_column() {
        let dir = tempfile::tempdir().expect("tempdir");
        let mut store = store(dir.path());
        let stage = Marks(Params {
            fail: false,
            fail_finish: false,
            misnamed: true,
        });
        let err = run_stage(&mut store, &stage, RunOptions::new(1), &NoProgress);
        let err = err.err().map(|e| e.to_string());
        assert_eq!(
            err.as_deref(),
            Some("stage `marks`: its kernel calls itself by another name")
        );
        assert!(!store.has_column(&MARK));
    }

    #[test]
    fn a_column_not_declared_is_missing() {
        let columns = StageColumns {
            columns: Vec::new(),
        };
        let err = columns.get(&MARK).err().map(|e| e.to_string());
        assert_eq!(
            err.as_deref(),
            Some("store has no `mark.u8` column (run the pass that computes it first)")
        );
    }
}
