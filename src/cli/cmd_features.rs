//! `scanmesh features`: valley-ridge feature lines (paper 5) as polylines.

use super::args::{FitArgs, Thresholds};
use super::stdout::outln;
use anyhow::{Context, Result};
use clap::Args;
use scanmesh::features::extract::extract_lines;
use scanmesh::io::place;
use scanmesh::store::Kept;
use std::path::PathBuf;

super::command::command_args!(FeaturesArgs => run, run_dir, plans |_c| scanmesh::features::params::FeatureParams::default().cost());
#[derive(Args)]
pub struct FeaturesArgs {
    /// Input point file or store directory.
    pub input: PathBuf,
    /// Output lines: .ply (vertex x y z double; edge vertex1 vertex2 int,
    /// kind uchar 1 ridge / 2 valley) or .obj (`l` records).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Print a JSON summary instead of the one-line report.
    #[arg(long)]
    json: bool,
    /// Write PLY as ASCII instead of binary.
    #[arg(long)]
    ascii: bool,
    #[command(flatten)]
    fit: FitArgs,
    #[command(flatten)]
    thresholds: Thresholds,
    #[command(flatten)]
    pub common: super::CommonArgs,
    #[command(flatten)]
    pub run: super::RunDirArgs,
}

pub fn run(a: FeaturesArgs) -> Result<()> {
    let s = a.common.settings_in(&a.run)?.no_bars_if(a.json);
    s.no_keep("feature lines")?;
    let params = a.thresholds.params(a.fit.params()?)?;
    place::check_distinct(&a.input, &a.output)?;
    let format = scanmesh::io::mesh_format(&a.output, a.ascii)?;
    let progress = s.progress();
    let places = (a.input.as_path(), a.output.as_path());
    let mut run = s.job().open(places, params.cost(), Kept::Nothing)?;
    let store = &mut run.ws.store;
    let (graph, report) = extract_lines(store, &params, run.opts, progress)?;
    graph
        .write(&a.output, store.origin(), format)
        .with_context(|| format!("writing {}", a.output.display()))?;
    let summary = s.closing(&report, &a.output);
    if a.json {
        outln!("{}", serde_json::to_string_pretty(&summary.json())?)?;
    } else {
        s.summary(summary);
    }
    Ok(())
}
