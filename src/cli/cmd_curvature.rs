//! `scanmesh curvature`: per-point principal, mean and Gaussian curvature
//! and the MLS residual (paper 5 section 2), in input order.

use anyhow::Result;
use clap::Args;
use scanmesh::features::compute_curvature;
use scanmesh::features::export::{curvature_output, write_curvature};
use scanmesh::rundir::{Computing, Hear};
use scanmesh::store::{PointStore, Rows};
use std::path::PathBuf;

super::command::command_args!(CurvatureArgs => run, run_dir, plans |_c| scanmesh::rundir::PointRun::cost(scanmesh::features::CurvatureParams::default().cost()));
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
    let params = a.fit.params()?;
    let spec = curvature_output(&a.output)?;
    let compute = |store: &mut PointStore, c: Computing| -> Result<_> {
        Ok(compute_curvature(store, &params, c.opts, c.progress)?)
    };
    let write = |store: &PointStore, to: &Rows, _: &dyn Hear| -> Result<_> {
        Ok(write_curvature(store, &spec, to)?)
    };
    let paths = (a.input.as_path(), a.output.as_path());
    a.common
        .per_point(&a.run, paths, params.cost(), compute, write, |r, _| r)
}
