//! A run's settings and the store it works on, opened within them: the
//! memory promise and the plan that keeps it, tile sizes, how the input is
//! read, the scratch directory and its limit, and the checks made before
//! any input is read (the output and scratch directories take files, the
//! disk plan fits the free space less what is kept free, a selection is
//! not given for a store); a store built once for repeated runs
//! ([`RunSettings::build_store_dir`]). The CLI maps its flags onto [`RunSettings`];
//! a library caller gets the same `--mem` promise the same way.

use super::{KernelCost, MemoryBudget, MemoryPlan, PipelineError, Progress, RunOptions};
use crate::io::{place, IoError, ReadOptions};
use crate::memory::{BudgetError, DiskPlan};
use crate::store::build::{build_store, scratch_store_dir_in, MAX_POINTS};
use crate::store::spacing::ensure_spacing;
use crate::store::{
    is_store, open_input, run_footprint, BuildOptions, Causes, Kept, PointStore, StoreError,
    TileTarget, Workspace,
};
use std::path::{Path, PathBuf};

/// What a run is promised and where it may work.
#[derive(Clone, Debug)]
pub struct RunSettings {
    /// The memory promise (`--mem`) and the threads (`--threads`).
    pub budget: MemoryBudget,
    /// Tiles of at most this many points, forced (`--tile-points`).
    pub tile_points: Option<u64>,
    /// How the input file is read: invalid records, E57 scans, selection.
    pub read: ReadOptions,
    /// Where the scratch store and spills go (default: beside the output).
    pub scratch_dir: Option<PathBuf>,
    /// The most scratch disk the run may use (`--scratch`).
    pub scratch_limit: Option<u64>,
    /// What a store built for the run keeps of its input
    /// ([`crate::store::BuildOptions::keep`]): the exact coordinates by
    /// default (a mesh's vertices may be input points), nothing for a run
    /// whose export reads the input again (`rundir::PointRun::run`).
    pub keep: Kept,
}

/// An open store with the plan a run keeps to.
pub struct Prepared {
    /// The store, and its scratch directory when it is the run's own.
    pub ws: Workspace,
    /// Run options whose tiles in flight fit the plan.
    pub opts: RunOptions,
    /// The memory plan.
    pub plan: MemoryPlan,
}

/// Why a run cannot start, or its store cannot be opened.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum WorkspaceError {
    /// No plan fits the memory promise.
    #[error(transparent)]
    Budget(#[from] BudgetError),
    /// The store cannot be built or opened.
    #[error(transparent)]
    Store(#[from] StoreError),
    /// A directory or the input cannot be used.
    #[error(transparent)]
    Io(#[from] IoError),
    /// The run options do not fit the plan.
    #[error(transparent)]
    Pipeline(#[from] PipelineError),
    /// The input cannot be read (the source says why).
    #[error("reading {path}")]
    Reading {
        /// The input.
        path: PathBuf,
        /// Why.
        #[source]
        source: StoreError,
    },
    /// A selection of points or scans was given for a store, which holds
    /// the points it was built from.
    #[error("{path}: {what} select {of}; a store holds the points it was built from")]
    SelectionOfAStore {
        /// The store.
        path: PathBuf,
        /// The options given ("--scans", "--classes and --returns").
        what: &'static str,
        /// What they select.
        of: &'static str,
    },
    /// The disk plan needs more scratch than the limit allows.
    #[error("--scratch {limit}: this run needs about {needed} of scratch disk (its disk plan; `scanmesh info --plan` prints it)", limit = crate::units::human_bytes(*limit), needed = crate::units::human_bytes(*needed))]
    ScratchLimit {
        /// The limit, in bytes.
        limit: u64,
        /// What the plan needs, in bytes.
        needed: u64,
    },
    /// A store is to be built in a directory that holds something.
    #[error("{}: exists and is not empty", path.display())]
    NotEmpty {
        /// The directory.
        path: PathBuf,
    },
    /// A directory cannot be listed.
    #[error(transparent)]
    List(#[from] std::io::Error),
    /// The disk plan does not fit the free space.
    #[error("not enough free space (--scratch-dir puts the scratch files elsewhere): {0}")]
    NoSpace(IoError),
}

impl WorkspaceError {
    /// What this error comes down to ([`Causes`]).
    pub fn causes(&self) -> Causes<'_> {
        match self {
            WorkspaceError::Budget(b) => Causes {
                budget: Some(b),
                input: None,
            },
            WorkspaceError::Store(e) | WorkspaceError::Reading { source: e, .. } => e.causes(),
            WorkspaceError::Io(e) => Causes {
                budget: None,
                input: Some(e),
            },
            _ => Causes::default(),
        }
    }
}

impl RunSettings {
    /// Settings with `budget` and every other choice the default.
    pub fn new(budget: MemoryBudget) -> Self {
        RunSettings {
            budget,
            tile_points: None,
            read: ReadOptions::default(),
            scratch_dir: None,
            scratch_limit: None,
            keep: Kept::Coordinates,
        }
    }

    /// Checks that some plan fits the promise whatever the point count
    /// (the fixed costs and the smallest tiles), before any input is read.
    pub fn check_floor(&self, cost: &KernelCost) -> Result<(), WorkspaceError> {
        MemoryPlan::new(self.budget, 0, cost)?;
        Ok(())
    }

    /// Tile sizes for a kernel: forced by `tile_points`, else from the plan.
    pub fn build_options(&self, cost: KernelCost) -> BuildOptions {
        let within = BuildOptions {
            keep: self.keep,
            ..BuildOptions::within(self.budget, cost)
        };
        match self.tile_points {
            Some(n) => BuildOptions {
                tiles: TileTarget::Points(n),
                ..within
            },
            None => within,
        }
    }

    /// Refuses a selection of points or scans for a store.
    pub fn check_selection(&self, input: &Path) -> Result<(), WorkspaceError> {
        let refuse = |what, of| WorkspaceError::SelectionOfAStore {
            path: input.to_path_buf(),
            what,
            of,
        };
        match is_store(input) {
            true if self.read.scans.is_some() => Err(refuse("--scans", "scans of an E57 input")),
            true if !self.read.select.is_all() => Err(refuse(
                "--classes and --returns",
                "points of a point file (give them to `scanmesh tile`)",
            )),
            _ => Ok(()),
        }
    }

    /// The store to work on (`input` itself when it is one, else a scratch
    /// store beside `output` built from the input file), its memory plan,
    /// and run options that keep the tiles in flight within it; with the
    /// scratch entries killed runs left that were removed on the way.
    pub fn open(
        &self,
        input: &Path,
        output: &Path,
        cost: KernelCost,
        progress: &dyn Progress,
    ) -> Result<(Prepared, Vec<PathBuf>), WorkspaceError> {
        self.check_floor(&cost)?;
        self.check_selection(input)?;
        let (scratch_dir, reclaimed) = self.check_places(input, output, &cost)?;
        let scratch = scratch_store_dir_in(&scratch_dir, output);
        let build = self.build_options(cost);
        let ws = open_input(input, &scratch, &build, self.read.clone(), progress)
            .map_err(|e| reading(input, e))?;
        Ok((self.prepare(ws, cost)?, reclaimed))
    }

    /// Builds a store at `dir` (which must not exist, or be empty) from the
    /// input file, with tiles sized for `cost` within the promise, and its
    /// spacing estimate, for repeated runs; a build that fails or is
    /// interrupted leaves no directory behind (a store without its manifest
    /// is no store).
    pub fn build_store_dir(
        &self,
        input: &Path,
        dir: &Path,
        cost: KernelCost,
        progress: &dyn Progress,
    ) -> Result<PointStore, WorkspaceError> {
        if dir.exists() && std::fs::read_dir(dir)?.next().is_some() {
            return Err(WorkspaceError::NotEmpty {
                path: dir.to_path_buf(),
            });
        }
        place::check_writable_dir(&place::directory_of(dir), "output")?;
        let building = crate::io::cleanup::register(dir);
        let mut reader = crate::io::open_reader(input, self.read.clone())?;
        self.check_floor(&cost)?;
        // A store for repeated runs serves exports without its input.
        let opts = BuildOptions {
            keep: Kept::All,
            ..self.build_options(cost)
        };
        let mut store = match build_store(reader.as_mut(), dir, &opts, progress) {
            Ok(store) => store,
            Err(e) => {
                let _ = std::fs::remove_dir_all(dir);
                return Err(e.into());
            }
        };
        ensure_spacing(&mut store)?;
        drop(building);
        Ok(store)
    }

    /// Checks, before any input is read, that the output and scratch
    /// directories take new files and (when the input says how many points
    /// it holds) have room for the run; returns the scratch directory and
    /// the scratch entries killed runs left there (removed).
    pub fn check_places(
        &self,
        input: &Path,
        output: &Path,
        cost: &KernelCost,
    ) -> Result<(PathBuf, Vec<PathBuf>), WorkspaceError> {
        place::check_output(output)?;
        let scratch_dir = match &self.scratch_dir {
            Some(d) => d.clone(),
            None => place::directory_of(output),
        };
        place::check_writable_dir(&scratch_dir, "scratch")?;
        let reclaimed = reclaim(&[&scratch_dir, &place::directory_of(output)]);
        let footprint = run_footprint(input, self.read.clone(), self.keep, Some(output), *cost)
            .map_err(|e| match is_store(input) {
                true => WorkspaceError::Store(e),
                false => reading(input, e),
            })?;
        let (count, store, cost) = (footprint.points, footprint.store_per_point, footprint.cost);
        // A count past what a store holds is refused later, as such.
        if let Some(n) = count.filter(|&n| n <= MAX_POINTS) {
            let disk = DiskPlan::new(n, store, &cost.under_budget(&self.budget, n));
            self.within_scratch_limit(disk.scratch_dir())?;
            let output_dir = place::directory_of(output);
            place::check_space(
                &scratch_dir,
                disk.scratch_dir(),
                &output_dir,
                disk.output_dir(),
                disk.one_volume(),
            )
            .map_err(WorkspaceError::NoSpace)?;
        }
        Ok((scratch_dir, reclaimed))
    }

    /// Checks, once the store is built, that the stages' scratch beside it
    /// and the output fit: a plan that needed the store's spacing (a
    /// `--cell` in the input's units) is known only now.
    pub fn check_stage_space(
        &self,
        store: &PointStore,
        output: &Path,
        cost: &KernelCost,
    ) -> Result<(), WorkspaceError> {
        let cost = match store.checkpoints() {
            Some(_) => cost.in_run_dir(),
            None => *cost,
        };
        let cost = KernelCost {
            // Only a scratch store gives its positions up.
            export_frees_positions: cost.export_frees_positions && store.is_scratch(),
            ..cost.under_budget(&self.budget, store.len())
        };
        let disk = DiskPlan::new(store.len(), 0, &cost);
        self.within_scratch_limit(store.bytes_on_disk().saturating_add(disk.scratch_dir()))?;
        let output_dir = place::directory_of(output);
        let (scratch, out) = (disk.scratch_dir(), disk.output_dir());
        place::check_space(store.dir(), scratch, &output_dir, out, disk.one_volume())
            .map_err(WorkspaceError::NoSpace)
    }

    /// Refuses a run whose scratch would pass the limit.
    fn within_scratch_limit(&self, needed: u64) -> Result<(), WorkspaceError> {
        match self.scratch_limit {
            Some(limit) if needed > limit => Err(WorkspaceError::ScratchLimit { limit, needed }),
            _ => Ok(()),
        }
    }

    /// The plan and run options for an open store.
    pub fn prepare(&self, ws: Workspace, cost: KernelCost) -> Result<Prepared, WorkspaceError> {
        let (plan, opts) = self.plan_for(&ws.store, cost)?;
        Ok(Prepared { ws, opts, plan })
    }

    /// The memory plan for `store` and run options whose tiles in flight
    /// fit it.
    pub fn plan_for(
        &self,
        store: &PointStore,
        cost: KernelCost,
    ) -> Result<(MemoryPlan, RunOptions), WorkspaceError> {
        let plan = MemoryPlan::new(self.budget, store.len(), &cost)?;
        let largest = store.tiles().iter().map(|t| t.count).max().unwrap_or(0);
        let opts = RunOptions::planned(&plan, &cost, largest)?;
        Ok((plan, opts))
    }
}

fn reading(input: &Path, source: StoreError) -> WorkspaceError {
    WorkspaceError::Reading {
        path: input.to_path_buf(),
        source,
    }
}

/// What a caller says of the scratch entries [`reclaim`] removed, if any.
pub fn reclaimed_note(removed: &[PathBuf]) -> Option<String> {
    let names: Vec<String> = removed.iter().map(|p| p.display().to_string()).collect();
    (!removed.is_empty()).then(|| {
        let (n, names) = (removed.len(), names.join(", "));
        format!("removed {n} scratch entries that killed runs left: {names}")
    })
}

/// Removes what killed runs left in `dirs` (their scratch stores and
/// partial outputs), each directory once however it is named; returns
/// what was removed.
pub fn reclaim(dirs: &[&Path]) -> Vec<PathBuf> {
    let mut seen: Vec<PathBuf> = Vec::new();
    let mut removed = Vec::new();
    for dir in dirs {
        let dir = dir.canonicalize().unwrap_or_else(|_| dir.to_path_buf());
        if seen.contains(&dir) {
            continue;
        }
        removed.extend(crate::io::reclaim::reclaim_scratch(&dir));
        seen.push(dir);
    }
    removed
}
