//! `scanmesh neighbors`: every point's topological (paper 3) or k nearest
//! neighbours, in input order, as a binary CSR file or text.

use anyhow::{bail, Context, Result};
use clap::Args;
use scanmesh::io::place;
use scanmesh::neighbours::{compute_neighbours, NeighbourParams, OutputFormat, OutputOptions};
use scanmesh::spatial::HoodKind;
use scanmesh::store::Kept;
use std::path::PathBuf;

super::command::command_args!(NeighborsArgs => run, run_dir |_a| Ok(vec![scanmesh::rundir::StageId::NEIGHBOURS]), plans |_c| NeighbourParams::default().cost());
#[derive(Args)]
pub struct NeighborsArgs {
    /// Input point file or store directory.
    pub input: PathBuf,
    /// Output file (binary CSR, see `scanmesh::neighbours::csr`; or text).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Which neighbourhood: topological (paper 3, mean reverse shift) or
    /// the plain k nearest.
    #[arg(long, visible_alias = "neighbors", value_enum, default_value_t = HoodKind::Topological)]
    neighbours: HoodKind,
    /// Points per kNN query (paper 3: 8..30, usually 15).
    #[arg(long, default_value_t = 15)]
    k: usize,
    /// Output layout.
    #[arg(long, value_enum, default_value_t = OutputFormat::Csr)]
    format: OutputFormat,
    /// Write statistics (sizes, iterations, time) to this JSON file.
    #[arg(long)]
    summary: Option<PathBuf>,
    /// Cap on reverse-shift iterations (topological).
    #[arg(long, default_value_t = 10)]
    max_iterations: usize,
    #[command(flatten)]
    pub common: super::CommonArgs,
    #[command(flatten)]
    pub run: super::RunDirArgs,
}

impl NeighborsArgs {
    fn params(&self) -> Result<NeighbourParams> {
        let params = NeighbourParams::of(self.neighbours, self.k, self.max_iterations);
        params
            .validate()
            .with_context(|| format!("--k {}", self.k))?;
        Ok(params)
    }
}

pub fn run(a: NeighborsArgs) -> Result<()> {
    let s = a.common.settings_in(&a.run)?;
    s.no_keep("lists over the selected points only (keeping the others is not implemented for neighbors yet)")?;
    let params = a.params()?;
    place::check_distinct(&a.input, &a.output)?;
    if let Some(summary) = &a.summary {
        place::check_distinct(&a.input, summary)?;
        if summary == &a.output {
            bail!("--summary and -o name the same file");
        }
    }
    let progress = s.progress();
    let places = (a.input.as_path(), a.output.as_path());
    let mut run = s.job().open(places, params.cost(), Kept::Nothing)?;
    let out = OutputOptions {
        format: a.format,
        window_points: run.plan.window_points,
    };
    let report = compute_neighbours(
        &mut run.ws.store,
        &params,
        &a.output,
        &out,
        run.opts,
        progress,
    )
    .with_context(|| format!("writing {}", a.output.display()))?;
    let line = s.closing(&report, &a.output);
    if let Some(path) = &a.summary {
        report
            .write_summary(path, line.secs)
            .with_context(|| format!("writing {}", path.display()))?;
    }
    s.summary(line);
    Ok(())
}
