//! `scanmesh outliers`: statistical outlier scores (PCL's and Open3D's
//! rule) for every point, in input order, with the outliers flagged.

use anyhow::{Context, Result};
use clap::Args;
use scanmesh::io::place;
use scanmesh::outliers::{
    compute_outliers, outliers_output, write_outliers, OutlierParams, OutliersWritten, OUTLIER,
};
use std::path::PathBuf;

super::command::command_args!(OutliersArgs => run, run_dir);
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
    let s = a.common.settings_in(&a.run)?;
    let params = OutlierParams {
        k: a.k,
        ratio: a.ratio,
    };
    params.validate()?;
    place::check_distinct(&a.input, &a.output)?;
    let mut spec = outliers_output(&a.output)?;
    if a.drop {
        spec.drop_flagged = OUTLIER;
    }
    let progress = s.progress();
    let mut run = s.open_input(&a.input, &a.output, params.cost(), progress)?;
    let store = &mut run.ws.store;
    let report = compute_outliers(store, &params, run.opts, progress)?;
    let window = run.plan.window_points;
    let rows = write_outliers(store, &a.output, &spec, window, s.keep(&a.input), progress)
        .with_context(|| format!("writing {}", a.output.display()))?;
    let written = OutliersWritten {
        report: &report,
        rows,
        dropped: a.drop,
    };
    s.summary(s.closing(&written, &a.output));
    Ok(())
}
