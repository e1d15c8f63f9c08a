//! `scanmesh run-job DIR`: one part of the run kept in DIR, as the scripts
//! of `--emit` call it on each node: everything before a tile stage
//! (`--until`), some tiles of one (`--stage` with `--share` or `--tiles`),
//! or the rest of the run. The command line is the one DIR recorded, run
//! from the directory it was given in, on the input it was given (checked
//! unchanged).

use super::Cli;
use anyhow::{bail, Context, Result};
use clap::{Args, Parser};
use scanmesh::rundir::RunDir;
use scanmesh::store::{Job, TileSet};
use std::path::PathBuf;

super::command::command_args!(RunJobArgs => run);
#[derive(Args)]
pub struct RunJobArgs {
    /// Run directory (made by a command given --run-dir, or its --emit).
    dir: PathBuf,
    /// The tile stage this job computes tiles of (as `status` names it).
    #[arg(long, requires = "tile_set")]
    stage: Option<String>,
    /// Tiles FIRST-LAST of --stage (0-based, inclusive).
    #[arg(long, value_parser = TileSet::parse_range, group = "tile_set")]
    tiles: Option<TileSet>,
    /// Share INDEX/COUNT of --stage's tiles, for array jobs.
    #[arg(long, value_parser = TileSet::parse_share, group = "tile_set")]
    share: Option<TileSet>,
    /// Do what comes before this tile stage, then stop.
    #[arg(long, conflicts_with = "stage")]
    until: Option<String>,
    /// Worker threads (default: all cores; at most 8 x the cores).
    #[arg(long)]
    threads: Option<usize>,
    /// No progress bars.
    #[arg(long, short)]
    quiet: bool,
}

pub fn run(a: RunJobArgs) -> Result<()> {
    let (run, id) = RunDir::recorded(&a.dir, env!("CARGO_PKG_VERSION"))?;
    std::env::set_current_dir(&id.cwd)
        .with_context(|| format!("the run's directory {}", id.cwd.display()))?;
    id.check_input()?;
    let mut args = vec!["scanmesh".to_string()];
    args.extend(id.args.iter().cloned());
    args.extend(["--run-dir".into(), run.dir().to_string_lossy().into_owned()]);
    if a.quiet {
        args.push("--quiet".into());
    }
    if let Some(t) = a.threads {
        args.extend(["--threads".into(), t.to_string()]);
    }
    let mut command = Cli::try_parse_from(&args)
        .with_context(|| format!("{}: the recorded command line", a.dir.display()))?
        .command;
    let Some(run) = command.args_mut().run_dir_mut() else {
        bail!("{}: the recorded command keeps no run", a.dir.display());
    };
    run.job = Job::of(a.stage.as_deref(), a.tiles.or(a.share), a.until.as_deref());
    // Refused here, before the job is logged as started: --threads from
    // the script, --mem from the recorded command, against this node.
    if let Some(common) = command.args().common() {
        common.mem_and_threads(false)?;
    }
    super::run_in_dir::run_in_dir(command, args[1..].to_vec())
}
