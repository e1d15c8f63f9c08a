//! `scanmesh curvature`: per-point principal, mean and Gaussian curvature
//! and the MLS residual (paper 5 section 2), in input order.

use anyhow::{Context, Result};
use clap::Args;
use scanmesh::features::compute_curvature;
use scanmesh::features::export::{curvature_output, write_curvature};
use scanmesh::io::place;
use std::path::PathBuf;

super::command::command_args!(CurvatureArgs => run, run_dir);
#[derive(Args)]
pub struct CurvatureArgs {
    /// Input point file or store directory.
    pub input: PathBuf,
    /// Output: x y z k1 k2 H K residual flags per point, in input order;
    /// .ply, .pcd, .las or .laz (LAS: the values as extra bytes, a LAS
    /// input's own records kept as they came).
    #[arg(short, long)]
    pub output: PathBuf,
    #[command(flatten)]
    fit: super::args::FitArgs,
    #[command(flatten)]
    pub common: super::CommonArgs,
    #[command(flatten)]
    pub run: super::RunDirArgs,
}

pub fn run(a: CurvatureArgs) -> Result<()> {
    let s = a.common.settings_in(&a.run)?;
    let params = a.fit.params()?;
    place::check_distinct(&a.input, &a.output)?;
    let spec = curvature_output(&a.output)?;
    let progress = s.progress();
    let mut run = s.open_input(&a.input, &a.output, params.cost(), progress)?;
    let store = &mut run.ws.store;
    let report = compute_curvature(store, &params, run.opts, progress)?;
    let window = run.plan.window_points;
    write_curvature(store, &a.output, &spec, window, s.keep(&a.input), progress)
        .with_context(|| format!("writing {}", a.output.display()))?;
    s.summary(s.closing(&report, &a.output));
    Ok(())
}
