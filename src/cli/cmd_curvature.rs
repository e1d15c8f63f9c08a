//! `scanmesh curvature`: per-point principal, mean and Gaussian curvature
//! and the MLS residual (paper 5 section 2), in input order.

use anyhow::{bail, Context, Result};
use clap::{Args, ValueEnum};
use scanmesh::features::curvature::CurvatureReport;
use scanmesh::features::export::{curvature_output, write_curvature};
use scanmesh::features::{compute_curvature, CurvatureParams, HoodChoice};
use scanmesh::normals::{NormalParams, Orientation};
use std::path::{Path, PathBuf};
use std::time::Instant;

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
    fit: FitArgs,
    #[command(flatten)]
    pub common: super::CommonArgs,
    #[command(flatten)]
    pub run: super::RunDirArgs,
}

/// The curvature fit's options (shared with `features`).
#[derive(Args, Clone)]
pub struct FitArgs {
    /// Neighbourhood of the quadratic fit: every point within --radius mean
    /// spacings (paper 5's default), the --k nearest (its choice for
    /// curvature-adaptive sampling), or paper 3's topological neighbours.
    #[arg(long, visible_alias = "neighbors", value_enum, default_value_t = FitHood::Radius)]
    neighbours: FitHood,
    /// Fit radius in mean spacings d (d = mean distance to the 6 nearest
    /// neighbours; paper: 2..4). Default: 3, widened up to 4.5 on noisy
    /// input by the normals pass's noise estimate.
    #[arg(long)]
    radius: Option<f64>,
    /// Neighbours of the fit (--neighbours knn; per query for topological).
    #[arg(long, default_value_t = 15)]
    k: usize,
    /// Cap on reverse-shift iterations (--neighbours topological).
    #[arg(long, default_value_t = 10)]
    max_iterations: usize,
    /// How normals get their sign when the input has none computed:
    /// paper 5's six sources, or the spanning tree (paper 1).
    #[arg(long, value_enum, default_value_t = FitOrient::Mst)]
    orient: FitOrient,
}

#[derive(Clone, Copy, ValueEnum)]
enum FitHood {
    Radius,
    Knn,
    Topological,
}

#[derive(Clone, Copy, ValueEnum)]
enum FitOrient {
    /// Minimum spanning tree (paper 1), the project's default.
    Mst,
    /// Paper 5's six sources.
    Sources,
}

impl FitArgs {
    pub fn params(&self) -> Result<CurvatureParams> {
        let hood = match self.neighbours {
            FitHood::Radius => match self.radius {
                Some(spacings) => HoodChoice::Radius { spacings },
                None => HoodChoice::Auto,
            },
            FitHood::Knn => HoodChoice::Knn { k: self.k },
            FitHood::Topological => HoodChoice::Topological {
                k: self.k,
                max_iterations: self.max_iterations,
            },
        };
        if let Err(e) = hood.validate() {
            bail!("{e}");
        }
        let orientation = match self.orient {
            FitOrient::Mst => Orientation::SpanningTree,
            FitOrient::Sources => Orientation::SixSources {
                tau: scanmesh::normals::sources::DEFAULT_TAU,
            },
        };
        Ok(CurvatureParams {
            hood,
            normals: NormalParams {
                orientation,
                ..NormalParams::default()
            },
        })
    }
}

pub fn run(a: CurvatureArgs) -> Result<()> {
    let s = a.common.settings_in(&a.run)?;
    let params = a.fit.params()?;
    s.init_threads();
    super::check_distinct(&a.input, &a.output)?;
    let spec = curvature_output(&a.output)?;
    let progress = super::progress::progress(s.quiet);
    let t0 = Instant::now();
    let mut run = s.open_input(&a.input, &a.output, params.cost(), progress.as_ref())?;
    let store = &mut run.ws.store;
    let report = compute_curvature(store, &params, run.opts, progress.as_ref())?;
    let read = s.read_options();
    let keep = s.keep_unselected.then_some((a.input.as_path(), &read));
    let window = run.plan.window_points;
    write_curvature(store, &a.output, &spec, window, keep, progress.as_ref())
        .with_context(|| format!("writing {}", a.output.display()))?;
    super::report::unselected_kept(s.keep_unselected);
    print_summary(&report, t0.elapsed().as_secs_f64(), &a.output);
    Ok(())
}

fn print_summary(r: &CurvatureReport, secs: f64, out: &Path) {
    let m = &r.meta;
    let [sparse, degenerate, ill, unoriented] = m.flagged;
    super::report::summary(format!(
        "curvature: {} points, {} tiles ({} reloaded), d {:.4e}, {}, |k| median {:.4e} p90 {:.4e}, \
         residual RMS {:.4e} max {:.4e}, flagged: {} sparse, {} degenerate, {} ill-conditioned, \
         {} unoriented, {:.2} s, peak {} -> {}",
        m.points,
        r.tiles,
        r.run.retries,
        m.spacing,
        m.resolved,
        m.dominant_quantile(0.5),
        m.dominant_quantile(0.9),
        m.rms,
        m.max_error,
        sparse,
        degenerate,
        ill,
        unoriented,
        secs,
        super::peak(),
        out.display()
    ));
}
