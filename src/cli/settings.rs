//! The options every processing command shares (`CommonArgs`, the run
//! directory's `RunDirArgs`, the selection's `SelectArgs`) and their
//! mapping onto the library's run settings ([`Settings`]), which the
//! commands run in: the per-point shell (`CommonArgs::per_point`), the
//! library's `PointRun` heard by them, the summary line.

use super::report;
use anyhow::{bail, Context, Result};
use clap::Args;
use scanmesh::io::keep::Unselected;
use scanmesh::io::{InvalidPolicy, ReadOptions, Returns, Selection};
use scanmesh::memory::{cores, too_many_threads, too_much_memory};
use scanmesh::mesh::MeshAudit;
use scanmesh::pipeline::{reclaimed_note, KernelCost, MemoryBudget, NoProgress};
use scanmesh::pipeline::{Progress, RunSettings};
use scanmesh::rundir::{Computing, Hear, PointRun, Said, Scheduler, Session};
use scanmesh::runlog::{SharedRunLog, StageLines};
use scanmesh::store::{Job, PointStore, Rows};
use scanmesh::summary::Summary;
use std::fmt::Display;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Options every processing command takes.
#[derive(Args, Clone, Debug)]
pub struct CommonArgs {
    /// Peak memory (RSS) promise, e.g. 256MiB, 2GiB; at most the
    /// machine's RAM or its cgroup limit, whichever is smaller.
    #[arg(long, default_value = "1GiB")]
    pub(super) mem: String,
    /// Worker threads (default: all cores; at most 8 x the cores).
    #[arg(long)]
    pub(super) threads: Option<usize>,
    /// Force tiles of at most this many points (tests, benches).
    #[arg(long)]
    pub(super) tile_points: Option<u64>,
    /// No progress bars.
    #[arg(long, short)]
    pub(super) quiet: bool,
    /// Drop points with NaN/inf coordinates, and a text file's last line
    /// without end of line (it may be cut short), instead of failing; the
    /// summary line and --report say how many.
    #[arg(long)]
    pub(super) skip_invalid: bool,
    /// E57 input: read only these scans (indices as `scanmesh info` lists
    /// them, e.g. 0,2), in file order.
    #[arg(long, value_name = "I,J,...", value_delimiter = ',')]
    pub(super) scans: Option<Vec<usize>>,
    #[command(flatten)]
    pub(super) select: SelectArgs,
    /// What a per-point output (normals, curvature, outliers, convert) holds of
    /// the points --classes/--returns leave out: drop (default: the
    /// selected points only, as with --skip-invalid; the summary line
    /// counts the others) or keep (every input point in input order, the
    /// unselected ones with NaN values and flag 128).
    #[arg(long, value_enum, default_value_t = Unselected::Drop)]
    pub(super) unselected: Unselected,
    /// Directory for the scratch store and spill files (default: beside
    /// the output), for outputs on a small or slow volume.
    #[arg(long, value_name = "DIR")]
    pub(super) scratch_dir: Option<PathBuf>,
    /// Most scratch disk the run may use, e.g. 50GiB (a quota below the
    /// volume's free space): refused before it starts when its disk plan
    /// (`info --plan`) needs more. Default: the free space, less a
    /// twentieth of it (64 MiB to 4 GiB) kept free for the rest of the
    /// machine.
    #[arg(long, value_name = "SIZE")]
    pub(super) scratch: Option<String>,
    /// Write a JSON report of the run here: per stage wall and CPU time,
    /// peak RSS and disk traffic, the summary, the outcome, the version.
    #[arg(long, value_name = "FILE.json")]
    pub(super) report: Option<PathBuf>,
    /// What the run does and costs, for `--report` (begun when the
    /// command line is parsed).
    #[arg(skip)]
    pub(super) log: SharedRunLog,
}

/// The run directory's options, taken by the commands that can keep one
/// (normals, curvature, outliers, features, neighbors, reconstruct); the
/// others do not list them.
#[derive(Args, Clone, Debug, Default)]
pub struct RunDirArgs {
    /// Keep the run in DIR (its store, finished tiles, log): the same
    /// command again resumes where it stopped.
    #[arg(long, value_name = "DIR")]
    pub(super) run_dir: Option<PathBuf>,
    /// With --run-dir: discard what DIR holds and start afresh.
    #[arg(long, requires = "run_dir")]
    pub(super) restart: bool,
    /// With --run-dir: print a job script for GNU parallel or Slurm
    /// instead of running (tile stages as parallel jobs).
    #[arg(long, value_enum, requires = "run_dir")]
    pub(super) emit: Option<Scheduler>,
    /// With --emit: jobs per tile stage.
    #[arg(long, default_value_t = 16, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    pub(super) tasks: u32,
    /// The part of the run this process does (set by `run-job`).
    #[arg(skip)]
    pub(super) job: Job,
    /// The job in its run directory, once the run is begun there.
    #[arg(skip)]
    pub(super) session: Option<Session>,
}

/// Which points of the input to process (`--classes`, `--returns`),
/// taken by every command that reads a point file.
#[derive(Args, Clone, Debug, Default)]
pub struct SelectArgs {
    /// Process only points of these classification codes (e.g. 2,6:
    /// ground and buildings); the others are left out, counted on the
    /// summary line. An input without classification (XYZ, most PLY)
    /// is an error.
    #[arg(long, value_name = "C,D,...", value_delimiter = ',')]
    pub(super) classes: Option<Vec<u8>>,
    /// Process only these returns of each pulse: first (return number
    /// 1), last (return number = number of returns, LAS/LAZ) or all.
    #[arg(long, value_enum, default_value_t = Returns::All)]
    pub(super) returns: Returns,
}

impl SelectArgs {
    /// How to read the input: these points, and invalid records skipped
    /// (`--skip-invalid`) or refused.
    pub fn read(&self, skip_invalid: bool) -> ReadOptions {
        let policy = match skip_invalid {
            true => InvalidPolicy::Skip,
            false => InvalidPolicy::Reject,
        };
        ReadOptions {
            policy,
            select: self.selection(),
            ..ReadOptions::default()
        }
    }

    /// The selection the flags give.
    pub fn selection(&self) -> Selection {
        Selection {
            classes: self.classes.clone(),
            returns: self.returns,
        }
    }
}

/// Validated common options: the library's run settings, and what the
/// command line keeps beside them.
pub struct Settings {
    /// `--mem`, `--threads`, `--tile-points`, how the input is read
    /// (`--skip-invalid`, `--scans`, `--classes`, `--returns`),
    /// `--scratch-dir`, `--scratch`.
    pub lib: RunSettings,
    pub quiet: bool,
    /// `--unselected keep`, with a selection: per-point outputs write the
    /// points it leaves out too, flagged.
    pub keep_unselected: bool,
    /// This process's part of the run in its directory (`--run-dir`).
    pub run: Option<Session>,
    /// The run's log, for `--report`: its stages, summary line, what it left out.
    pub log: SharedRunLog,
    /// Progress bars (none with `--quiet`), every stage timed into `log`.
    pub(super) progress: Box<dyn Progress>,
    /// When the command began (its summary line's seconds).
    t0: Instant,
}

/// Bars on a terminal, nothing otherwise or when `quiet`; stage timings
/// instead when `SCANMESH_TIMINGS` asks for them.
pub(super) fn shown(quiet: bool) -> Box<dyn Progress> {
    match std::env::var_os("SCANMESH_TIMINGS") {
        // Asked for by name: whatever `--quiet` says.
        Some(_) => Box::new(StageLines::new(|line| eprintln!("{line}"))),
        None if quiet => Box::new(NoProgress),
        None => scanmesh::bars(),
    }
}

/// What of `--mem` and `--threads` this machine cannot keep, each naming
/// its option.
fn beyond_this_machine(mem: u64, threads: usize) -> impl Iterator<Item = String> {
    let threads = too_many_threads(threads).map(|why| format!("--threads {why}"));
    let mem = too_much_memory(mem).map(|why| format!("--mem {why}"));
    threads.into_iter().chain(mem)
}

/// `--mem` and `--threads` as numbers (the threads by default all cores).
pub(super) fn mem_and_threads(mem: &str, threads: Option<usize>) -> Result<(u64, usize)> {
    let bytes = scanmesh::units::parse_size(mem).with_context(|| format!("--mem {mem}"))?;
    match threads {
        Some(0) => bail!("--threads must be at least 1"),
        Some(t) => Ok((bytes, t)),
        None => Ok((bytes, cores())),
    }
}

impl CommonArgs {
    /// `--mem` and `--threads` as numbers, refused beyond this machine.
    /// With `--emit` the jobs run where the script sends them (a compute
    /// node may be larger than the login node), so they are only parsed
    /// here: [`CommonArgs::check_against_this_machine`] warns, and each
    /// job refuses them where it runs.
    pub(super) fn mem_and_threads(&self, emit: bool) -> Result<(u64, usize)> {
        let (mem, threads) = mem_and_threads(&self.mem, self.threads)?;
        if !emit {
            if let Some(why) = beyond_this_machine(mem, threads).next() {
                bail!(why);
            }
        }
        Ok((mem, threads))
    }

    /// `--mem` and `--threads` checked against this machine: refused
    /// beyond it, or with `--emit` a warning on stderr for each.
    pub(super) fn check_against_this_machine(&self, emit: bool) -> Result<()> {
        let (mem, threads) = self.mem_and_threads(emit)?;
        if emit {
            for why in beyond_this_machine(mem, threads) {
                eprintln!("warning: {why} (--emit: each job checks it again where it runs)");
            }
        }
        Ok(())
    }

    /// The settings of a command that keeps no run directory.
    pub(super) fn settings(&self) -> Result<Settings> {
        self.settings_in(&RunDirArgs::default())
    }

    /// The settings of a command run in `run`'s directory, if it names one;
    /// rayon's pool sized to their threads (once per process).
    pub(super) fn settings_in(&self, run: &RunDirArgs) -> Result<Settings> {
        let (mem, threads) = self.mem_and_threads(run.emit.is_some())?;
        if self.tile_points == Some(0) {
            bail!("--tile-points must be at least 1");
        }
        let scratch_limit = self
            .scratch
            .as_deref()
            .map(|s| scanmesh::units::parse_size(s).with_context(|| format!("--scratch {s}")))
            .transpose()?;
        let read = ReadOptions {
            scans: self.scans.clone(),
            ..self.select.read(self.skip_invalid)
        };
        let settings = Settings {
            keep_unselected: self.unselected == Unselected::Keep && !read.select.is_all(),
            lib: RunSettings {
                budget: MemoryBudget::new(mem, threads),
                tile_points: self.tile_points,
                read,
                scratch_dir: self.scratch_dir.clone(),
                scratch_limit,
                keep: scanmesh::store::Kept::Coordinates,
            },
            quiet: self.quiet,
            run: run.session.clone(),
            log: self.log.clone(),
            progress: Box::new(self.log.timed(shown(self.quiet))),
            t0: Instant::now(),
        };
        // Only fails when a pool exists already, which is then kept.
        let _ = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build_global();
        Ok(settings)
    }

    /// Runs a command that writes one row per input point in its
    /// settings ([`PointRun`]), then prints the summary line of
    /// `line(report, written)`.
    pub fn per_point<R, W, L>(
        &self,
        run: &RunDirArgs,
        (input, output): (&Path, &Path),
        cost: KernelCost,
        compute: impl FnOnce(&mut PointStore, Computing<'_>) -> Result<R>,
        write: impl FnOnce(&PointStore, &Rows<'_>, &dyn Hear) -> Result<W>,
        line: impl FnOnce(R, W) -> L,
    ) -> Result<()>
    where
        for<'x> Summary<'x, L>: Display,
    {
        let s = self.settings_in(run)?;
        let write = |store: &PointStore, rows: &Rows, hear: &dyn Hear| {
            write(store, rows, hear).with_context(|| format!("writing {}", output.display()))
        };
        let (report, written) = s.job().run((input, output), cost, compute, write)?;
        s.summary(s.closing(&line(report, written), output));
        Ok(())
    }
}

impl Settings {
    /// Refuses `--unselected keep` for a command whose output has no row
    /// per point (`what` says what it writes).
    pub fn no_keep(&self, what: &str) -> Result<()> {
        if self.keep_unselected {
            bail!("--unselected keep: this command writes {what}, not a row per input point; leave it out (or use drop)");
        }
        Ok(())
    }

    /// The library's run in these settings, heard by them.
    pub fn job(&self) -> PointRun<'_> {
        PointRun {
            settings: &self.lib,
            session: self.run.as_ref(),
            keep_unselected: self.keep_unselected,
            progress: self.progress(),
            hear: self,
        }
    }

    /// Refuses `--scratch` for a command that keeps no scratch of its own
    /// to plan (its store or file is the output), rather than ignore it.
    pub fn no_scratch_limit(&self, command: &str) -> Result<()> {
        match self.lib.scratch_limit {
            Some(_) => anyhow::bail!(
                "--scratch: `{command}` writes no planned scratch (the limit is for normals, curvature, outliers, features, neighbors and reconstruct)"
            ),
            None => Ok(()),
        }
    }

    /// Removes what killed runs left in `dirs` (their scratch stores and
    /// partial outputs), saying so.
    pub fn reclaim(&self, dirs: &[&Path]) {
        self.say_reclaimed(&scanmesh::pipeline::reclaim(dirs));
    }

    fn say_reclaimed(&self, removed: &[PathBuf]) {
        if let Some(note) = reclaimed_note(removed).filter(|_| !self.quiet) {
            eprintln!("{note}");
        }
    }

    /// Prints the closing `line` (kept for `--report`), saying whether the
    /// output holds the unselected points.
    pub fn summary(&self, line: impl Display) {
        self.log.with(|l| l.unselected_kept(self.keep_unselected));
        report::summary(&self.log, line);
    }

    /// Prints a mesh's closing `line`, keeping the mesh's audit for `--report`.
    pub fn mesh_summary(&self, audit: &MeshAudit, line: impl Display) {
        self.log.with(|l| l.mesh_audit(audit));
        report::summary(&self.log, line);
    }

    /// Progress bars (or nothing, with `--quiet`), every stage timed into
    /// the run's log.
    pub fn progress(&self) -> &dyn Progress {
        self.progress.as_ref()
    }

    /// These settings without progress bars when `off` (`features
    /// --json`), the stages still timed into the run's log.
    pub fn no_bars_if(mut self, off: bool) -> Self {
        if off {
            self.progress = Box::new(self.log.timed(shown(true)));
        }
        self
    }

    /// Prints `note` on stderr, if any, unless `--quiet`.
    pub fn note(&self, note: Option<String>) {
        if let Some(note) = note.filter(|_| !self.quiet) {
            eprintln!("note: {note}");
        }
    }

    /// The closing line of `report`, for this command, which wrote `output`.
    pub fn closing<'a, R>(&self, report: &'a R, output: &'a Path) -> Summary<'a, R> {
        Summary::since(report, self.t0, output)
    }
}

impl Hear for Settings {
    fn hear(&self, said: Said<'_>) {
        match said {
            Said::Reclaimed(files) => self.say_reclaimed(files),
            // The summary says how many input records the store lacks.
            Said::Opened(store) => {
                let m = store.manifest();
                self.log
                    .with(|l| l.input_skipped(&m.source, m.skipped_invalid, m.left_out));
            }
            Said::Note(note) => self.note(Some(note)),
        }
    }
}
