//! `scanmesh info`: what a file or a store holds, or the plan of a run
//! over it (`--plan`).

use super::stdout::outln;
use anyhow::{Context, Result};
use clap::Args;
use scanmesh::io::place;
use scanmesh::memory::{DiskPlan, MemoryBudget, PlanTable};
use scanmesh::store::describe::{describe_file, describe_store, footprint_to_plan};
use scanmesh::store::is_store;
use std::path::{Path, PathBuf};

super::command::command_args!(InfoArgs => run);
#[derive(Args)]
pub struct InfoArgs {
    /// A point file (PLY, XYZ/CSV, LAS/LAZ, PCD, optionally .gz; E57, whose
    /// scans are listed) or a store directory.
    input: PathBuf,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
    /// No progress bar.
    #[arg(long, short)]
    quiet: bool,
    /// Print the memory plan of a run over this input instead (tiles,
    /// points per tile, the global pass's mode, bytes per stage), without
    /// running it.
    #[arg(long)]
    plan: bool,
    /// The command whose plan to print (with --plan).
    #[arg(long, default_value = "normals", value_parser = super::plannable_names())]
    command: String,
    /// Memory promise to plan for (with --plan).
    #[arg(long, default_value = "1GiB")]
    mem: String,
    /// Worker threads to plan for (with --plan; default: all cores).
    #[arg(long)]
    threads: Option<usize>,
    /// The output to plan for (with --plan): its format sets the output's
    /// share of the disk plan (a LAS or LAZ written from its own format is
    /// planned from the input's bytes per point, as the run plans it;
    /// otherwise a PLY row).
    #[arg(long, short)]
    output: Option<PathBuf>,
    /// Plan `reconstruct --closed` (with --plan --command reconstruct).
    #[arg(long)]
    closed: bool,
    /// Count points with NaN/inf coordinates (and a last line cut short)
    /// as a processing command would drop them with --skip-invalid,
    /// instead of failing (`skipped_invalid`).
    #[arg(long)]
    skip_invalid: bool,
    #[command(flatten)]
    select: super::SelectArgs,
}

pub fn run(a: InfoArgs) -> Result<()> {
    if a.plan {
        let (mem, threads) = super::mem_and_threads(&a.mem, a.threads)?;
        let progress = super::shown(a.quiet);
        let read = a.select.read(a.skip_invalid);
        let mut planned = super::plannable().into_iter();
        let cost = planned.find_map(|(name, cost)| (name == a.command).then(|| cost(a.closed)));
        let cost = cost
            .flatten()
            .context("--command: not a plannable command")?;
        let output = a.output.as_deref();
        let (points, run) = footprint_to_plan(&a.input, read, output, cost, progress.as_ref())?;
        let budget = MemoryBudget::new(mem, threads);
        let table = PlanTable::new(budget, points, run.store_per_point, run.cost)?;
        outln!("{table}")?;
        return match &a.output {
            Some(output) => outln!("{}", room_for(table.disk(), output)),
            None => Ok(()),
        };
    }
    let report = if is_store(&a.input) {
        describe_store(&a.input, &a.select.selection())?
    } else {
        let progress = super::shown(a.quiet);
        describe_file(&a.input, a.select.read(a.skip_invalid), progress.as_ref())?
    };
    match a.json {
        true => outln!("{}", serde_json::to_string_pretty(report.json())?),
        false => outln!("{report}"),
    }
}

/// Whether the output's volume (the scratch directory's too, by default)
/// has room for the disk plan now, by the check a run makes before it
/// reads its input.
fn room_for(disk: &DiskPlan, output: &Path) -> String {
    let dir = place::directory_of(output);
    let (scratch, out) = (disk.scratch_dir(), disk.output_dir());
    match place::check_space(&dir, scratch, &dir, out, disk.one_volume()) {
        Ok(()) => format!("room on disk: {} has it now", dir.display()),
        Err(e) => {
            format!("room on disk: none, a run would be refused before it reads its input: {e}")
        }
    }
}
