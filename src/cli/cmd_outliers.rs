//! `scanmesh outliers`: statistical outlier scores (PCL's and Open3D's
//! rule) for every point, in input order, with the outliers flagged.

use anyhow::{Context, Result};
use clap::Args;
use scanmesh::outliers::{
    compute_outliers, outliers_output, write_outliers, OutlierParams, OutlierReport, OUTLIER,
};
use std::path::{Path, PathBuf};
use std::time::Instant;

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
    s.init_threads();
    super::check_distinct(&a.input, &a.output)?;
    let mut spec = outliers_output(&a.output)?;
    if a.drop {
        spec.drop_flagged = OUTLIER;
    }
    let progress = super::progress::progress(s.quiet);
    let t0 = Instant::now();
    let mut run = s.open_input(&a.input, &a.output, params.cost(), progress.as_ref())?;
    let store = &mut run.ws.store;
    let report = compute_outliers(store, &params, run.opts, progress.as_ref())?;
    let read = s.read_options();
    let keep = s.keep_unselected.then_some((a.input.as_path(), &read));
    let window = run.plan.window_points;
    let rows = write_outliers(store, &a.output, &spec, window, keep, progress.as_ref())
        .with_context(|| format!("writing {}", a.output.display()))?;
    super::report::unselected_kept(s.keep_unselected);
    let secs = t0.elapsed().as_secs_f64();
    print_summary(&report, &params, secs, (rows, a.drop), &a.output);
    Ok(())
}

fn print_summary(r: &OutlierReport, p: &OutlierParams, secs: f64, rows: (u64, bool), out: &Path) {
    let share = 100.0 * r.outliers as f64 / r.points.max(1) as f64;
    let rule = match r.not_judged == r.points {
        true => format!(": none judged, every point has fewer than {} neighbours", p.k),
        false => format!(
            " with a mean distance to their {} nearest above {:.4e} (mean {:.4e} + {} x std {:.4e}), \
             {} not judged (fewer than {} neighbours)",
            p.k, r.threshold, r.mean, p.ratio, r.std_dev, r.not_judged, p.k
        ),
    };
    let written = match rows {
        (n, true) => format!("{n} rows written, the outliers left out"),
        (n, false) => format!("{n} rows written"),
    };
    super::report::summary(format!(
        "outliers: {} of {} points ({share:.2} %){rule}, {} tiles ({} reloaded), {written}, \
         {secs:.2} s, peak {} -> {}",
        r.outliers,
        r.points,
        r.run.tiles,
        r.run.retries,
        super::peak(),
        out.display()
    ));
}
