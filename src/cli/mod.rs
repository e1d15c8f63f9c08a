//! Command-line arguments (raw, as clap parses them) and their validation
//! into [`Settings`], then dispatch to one module per command.

mod args;
mod cmd_convert;
mod cmd_curvature;
mod cmd_demo;
mod cmd_eval;
mod cmd_features;
mod cmd_info;
mod cmd_neighbors;
mod cmd_normals;
mod cmd_outliers;
mod cmd_reconstruct;
mod cmd_render;
mod cmd_run_job;
mod cmd_status;
mod cmd_tile;
mod command;
mod hints;
mod report;
mod run_in_dir;
mod stdout;

pub use stdout::closed as stdout_closed;

use anyhow::{bail, Context, Result};
use clap::{Args, Parser, Subcommand};
use command::CommandArgs;
use scanmesh::io::keep::Unselected;
use scanmesh::io::place;
use scanmesh::io::{InvalidPolicy, ReadOptions, Returns, Selection};
use scanmesh::memory::{cores, too_many_threads, too_much_memory, within_promise};
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

#[derive(Parser)]
#[command(
    name = "scanmesh",
    version,
    about = "Normals, neighbourhoods and surfaces from huge laser scans, out of core",
    long_about = "Normals, neighbourhoods and surfaces from huge laser scans, out of core.\n\n\
        Inputs: PLY (ascii/binary, .gz), XYZ/CSV text (.gz), LAS/LAZ, PCD, E57 (all scans, or --scans), or a point store \
        built by `scanmesh tile`. Memory stays within --mem whatever the input size."
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

/// The command table: one row per command, its help and its arguments'
/// type, which answers the rest ([`command::CommandArgs`]).
macro_rules! commands {
    ($($(#[$meta:meta])* $variant:ident($args:ty),)*) => {
        #[derive(Subcommand)]
        enum Command {
            $($(#[$meta])* $variant($args),)*
        }

        impl Command {
            fn args(&self) -> &dyn CommandArgs {
                match self {
                    $(Command::$variant(a) => a,)*
                }
            }

            fn args_mut(&mut self) -> &mut dyn CommandArgs {
                match self {
                    $(Command::$variant(a) => a,)*
                }
            }

            /// Runs the command in this process.
            fn dispatch(self) -> Result<()> {
                match self {
                    $(Command::$variant(a) => a.run(),)*
                }
            }
        }

        /// The commands a run of can be planned before it runs (`info
        /// --plan --command`), by name, with their default cost.
        fn plannable() -> Vec<(String, fn(bool) -> Option<KernelCost>)> {
            let costs: Vec<fn(bool) -> Option<KernelCost>> =
                vec![$(<$args as CommandArgs>::planned_cost,)*];
            let names = [$(stringify!($variant),)*].map(kebab_case);
            names.into_iter().zip(costs).filter(|(_, cost)| cost(false).is_some()).collect()
        }
    };
}

commands! {
    /// Format, point count, bounding box and spacing of a file or store.
    Info(cmd_info::InfoArgs),
    /// Convert between point formats, streaming (PLY, XYZ/CSV, LAS/LAZ, PCD, E57).
    Convert(cmd_convert::ConvertArgs),
    /// Build a tiled point store (a directory) for repeated runs.
    Tile(cmd_tile::TileArgs),
    /// Oriented normals for every point, written in input order.
    Normals(cmd_normals::NormalsArgs),
    /// Per-point principal, mean and Gaussian curvature (paper 5), in input order.
    Curvature(cmd_curvature::CurvatureArgs),
    /// Statistical outlier scores (PCL's and Open3D's rule), outliers flagged, in input order.
    Outliers(cmd_outliers::OutliersArgs),
    /// Valley-ridge feature lines (paper 5) as polylines (.ply edges or .obj lines).
    Features(cmd_features::FeaturesArgs),
    /// Topological (paper 3) or k nearest neighbours of every point, in input order.
    #[command(visible_alias = "neighbours")]
    Neighbors(cmd_neighbors::NeighborsArgs),
    /// A triangle mesh from a point cloud (implicit: paper 1).
    Reconstruct(cmd_reconstruct::ReconstructArgs),
    /// A PNG of points, feature lines and meshes (the project's own rasteriser).
    Render(cmd_render::RenderArgs),
    /// Mesh quality, and distances to a reference mesh or point set.
    Eval(cmd_eval::EvalArgs),
    /// Run the main job on a sample embedded in the binary.
    Demo(cmd_demo::DemoArgs),
    /// Do one part of a run kept in a run directory (what --emit's
    /// scripts call on each node).
    RunJob(cmd_run_job::RunJobArgs),
    /// Stages, tiles done, failures and time left of a run directory.
    Status(cmd_status::StatusArgs),
}

/// `RunJob` as clap names its subcommand: `run-job`.
fn kebab_case(name: &str) -> String {
    let dash = |i, c: char| (i > 0 && c.is_uppercase()).then_some('-');
    let chars = name.char_indices();
    chars
        .flat_map(|(i, c)| dash(i, c).into_iter().chain(c.to_lowercase()))
        .collect()
}

/// The names of the commands `info --plan --command` can plan.
fn plannable_names() -> clap::builder::PossibleValuesParser {
    plannable()
        .into_iter()
        .map(|(name, _)| name)
        .collect::<Vec<_>>()
        .into()
}

/// Options every processing command takes.
#[derive(Args, Clone, Debug)]
pub struct CommonArgs {
    /// Peak memory (RSS) promise, e.g. 256MiB, 2GiB; at most the
    /// machine's RAM or its cgroup limit, whichever is smaller.
    #[arg(long, default_value = "1GiB")]
    mem: String,
    /// Worker threads (default: all cores; at most 8 x the cores).
    #[arg(long)]
    threads: Option<usize>,
    /// Force tiles of at most this many points (tests, benches).
    #[arg(long)]
    tile_points: Option<u64>,
    /// No progress bars.
    #[arg(long, short)]
    quiet: bool,
    /// Drop points with NaN/inf coordinates, and a text file's last line
    /// without end of line (it may be cut short), instead of failing; the
    /// summary line and --report say how many.
    #[arg(long)]
    skip_invalid: bool,
    /// E57 input: read only these scans (indices as `scanmesh info` lists
    /// them, e.g. 0,2), in file order.
    #[arg(long, value_name = "I,J,...", value_delimiter = ',')]
    scans: Option<Vec<usize>>,
    #[command(flatten)]
    select: SelectArgs,
    /// What a per-point output (normals, curvature, outliers, convert) holds of
    /// the points --classes/--returns leave out: drop (default: the
    /// selected points only, as with --skip-invalid; the summary line
    /// counts the others) or keep (every input point in input order, the
    /// unselected ones with NaN values and flag 128).
    #[arg(long, value_enum, default_value_t = Unselected::Drop)]
    unselected: Unselected,
    /// Directory for the scratch store and spill files (default: beside
    /// the output), for outputs on a small or slow volume.
    #[arg(long, value_name = "DIR")]
    scratch_dir: Option<PathBuf>,
    /// Most scratch disk the run may use, e.g. 50GiB (a quota below the
    /// volume's free space): refused before it starts when its disk plan
    /// (`info --plan`) needs more. Default: the free space, less a
    /// twentieth of it (64 MiB to 4 GiB) kept free for the rest of the
    /// machine.
    #[arg(long, value_name = "SIZE")]
    scratch: Option<String>,
    /// Write a JSON report of the run here: per stage wall and CPU time,
    /// peak RSS and disk traffic, the summary, the outcome, the version.
    #[arg(long, value_name = "FILE.json")]
    report: Option<PathBuf>,
    /// What the run does and costs, for `--report` (begun when the
    /// command line is parsed).
    #[arg(skip)]
    log: SharedRunLog,
}

/// The run directory's options, taken by the commands that can keep one
/// (normals, curvature, outliers, features, neighbors, reconstruct); the
/// others do not list them.
#[derive(Args, Clone, Debug, Default)]
pub struct RunDirArgs {
    /// Keep the run in DIR (its store, finished tiles, log): the same
    /// command again resumes where it stopped.
    #[arg(long, value_name = "DIR")]
    run_dir: Option<PathBuf>,
    /// With --run-dir: discard what DIR holds and start afresh.
    #[arg(long, requires = "run_dir")]
    restart: bool,
    /// With --run-dir: print a job script for GNU parallel or Slurm
    /// instead of running (tile stages as parallel jobs).
    #[arg(long, value_enum, requires = "run_dir")]
    emit: Option<Scheduler>,
    /// With --emit: jobs per tile stage.
    #[arg(long, default_value_t = 16, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    tasks: u32,
    /// The part of the run this process does (set by `run-job`).
    #[arg(skip)]
    job: Job,
    /// The job in its run directory, once the run is begun there.
    #[arg(skip)]
    session: Option<Session>,
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
    classes: Option<Vec<u8>>,
    /// Process only these returns of each pulse: first (return number
    /// 1), last (return number = number of returns, LAS/LAZ) or all.
    #[arg(long, value_enum, default_value_t = Returns::All)]
    returns: Returns,
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
    progress: Box<dyn Progress>,
    /// When the command began (its summary line's seconds).
    t0: Instant,
}

/// Bars on a terminal, nothing otherwise or when `quiet`; stage timings
/// instead when `SCANMESH_TIMINGS` asks for them.
fn shown(quiet: bool) -> Box<dyn Progress> {
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
fn mem_and_threads(mem: &str, threads: Option<usize>) -> Result<(u64, usize)> {
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
    fn mem_and_threads(&self, emit: bool) -> Result<(u64, usize)> {
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
    fn check_against_this_machine(&self, emit: bool) -> Result<()> {
        let (mem, threads) = self.mem_and_threads(emit)?;
        if emit {
            for why in beyond_this_machine(mem, threads) {
                eprintln!("warning: {why} (--emit: each job checks it again where it runs)");
            }
        }
        Ok(())
    }

    /// The settings of a command that keeps no run directory.
    fn settings(&self) -> Result<Settings> {
        self.settings_in(&RunDirArgs::default())
    }

    /// The settings of a command run in `run`'s directory, if it names one;
    /// rayon's pool sized to their threads (once per process).
    fn settings_in(&self, run: &RunDirArgs) -> Result<Settings> {
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
}

impl CommonArgs {
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

pub fn run() -> Result<()> {
    let cli = Cli::parse();
    let common = cli.command.args().common().cloned();
    let report = common.as_ref().and_then(|c| c.report.clone());
    if let Some(path) = &report {
        place::check_output(path)?;
    }
    // Before a run directory is made or written: a refused --mem must not
    // leave a run behind that the corrected command line then differs from.
    let emit = cli
        .command
        .args()
        .run_dir()
        .is_some_and(|r| r.emit.is_some());
    let checked = common
        .as_ref()
        .map_or(Ok(()), |c| c.check_against_this_machine(emit));
    let promised = common.as_ref().and_then(|c| c.mem_and_threads(emit).ok());
    let outcome = checked
        .and_then(|()| match cli.command {
            Command::RunJob(a) => cmd_run_job::run(a),
            Command::Status(a) => cmd_status::run(a),
            command => run_in_dir::run_in_dir(command, std::env::args().skip(1).collect()),
        })
        .map_err(hints::with_flag_hints)
        // `--mem` promises the peak RSS: a run that went over it fails,
        // though its outputs are whole.
        .and_then(|()| Ok(promised.map_or(Ok(()), |(mem, _)| within_promise(mem))?));
    if let Some(path) = &report {
        // Begun when the command line was parsed: the run's cost counts from there.
        let log = common.map(|c| c.log).unwrap_or_default();
        report::write(&log, path, &outcome)?;
    }
    outcome
}
