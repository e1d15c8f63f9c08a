//! `scanmesh outliers`: statistical outlier scores (PCL's and Open3D's
//! rule) for every point, in input order, with the outliers flagged.

use anyhow::Result;
use clap::Args;
use scanmesh::outliers::{
    compute_outliers, outliers_output, write_outliers, OutlierParams, OutliersWritten, OUTLIER,
};
use scanmesh::rundir::{Computing, Hear};
use scanmesh::store::{PointStore, Rows};
use std::path::PathBuf;

super::command::command_args!(OutliersArgs => run, run_dir, plans |_c| scanmesh::rundir::PointRun::cost(OutlierParams::default().cost()));
#[derive(Args)]
pub struct OutliersArgs {
    /// Input point file or store directory.
    pub input: PathBuf,
    /// Output: x y z outlier_score flags per point, in input order (flags:
    /// 1 outlier, 2 fewer than k neighbours in the cloud); .ply, .pcd,
    /// .las or .laz (LAS: extra bytes after a LAS input's own records).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Neighbours whose mean distance is a point's score (Open3D's
    /// nb_neighbors, PCL's mean_k).
    #[arg(long, default_value_t = 20)]
    k: usize,
    /// An outlier's score exceeds the mean score by more than this many
    /// standard deviations (Open3D's std_ratio, PCL's stddev_mul_thresh).
    #[arg(long, default_value_t = 2.0)]
    ratio: f64,
    /// Write only the points the rule keeps (the cleaned cloud, as PCL's
    /// and Open3D's filters return it), still in input order with their
    /// scores; a LAS input's records as they came.
    #[arg(long)]
    drop: bool,
    #[command(flatten)]
    pub common: super::CommonArgs,
    #[command(flatten)]
    pub run: super::RunDirArgs,
}

pub fn run(a: OutliersArgs) -> Result<()> {
    let params = OutlierParams {
        k: a.k,
        ratio: a.ratio,
    };
    params.validate()?;
    let mut spec = outliers_output(&a.output)?;
    if a.drop {
        spec.drop_flagged = OUTLIER;
    }
    let compute = |store: &mut PointStore, c: Computing| -> Result<_> {
        Ok(compute_outliers(store, &params, c.opts, c.progress)?)
    };
    let write = |store: &PointStore, to: &Rows, _: &dyn Hear| -> Result<_> {
        Ok(write_outliers(store, &spec, to)?)
    };
    let line = |report, rows| OutliersWritten {
        report,
        rows,
        dropped: a.drop,
    };
    let paths = (a.input.as_path(), a.output.as_path());
    a.common
        .per_point(&a.run, paths, params.cost(), compute, write, line)
}
