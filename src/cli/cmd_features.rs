//! `scanmesh features`: valley-ridge feature lines (paper 5) as polylines.

use super::stdout::outln;
use anyhow::{bail, Context, Result};
use clap::Args;
use scanmesh::features::extract::{extract_lines, FeaturesReport};
use scanmesh::features::params::FeatureParams;
use std::path::{Path, PathBuf};
use std::time::Instant;

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
    fit: super::cmd_curvature::FitArgs,
    #[command(flatten)]
    thresholds: Thresholds,
    #[command(flatten)]
    pub common: super::CommonArgs,
    #[command(flatten)]
    pub run: super::RunDirArgs,
}

/// Every threshold of paper 5, lengths in mean spacings d (defaults from
/// the data; see `features::params`).
#[derive(Args)]
struct Thresholds {
    /// Curvature threshold alpha (absolute, 1/length; default: the larger
    /// of the 70th percentile of |k| and 8 x the fit-noise curvature).
    #[arg(long)]
    alpha: Option<f64>,
    /// Enhancement radius phi (d).
    #[arg(long, default_value_t = FeatureParams::default().phi)]
    phi: f64,
    /// Growth-circle radius R (d).
    #[arg(long, default_value_t = FeatureParams::default().growth_radius)]
    growth_radius: f64,
    /// Corner merge distance epsilon (d).
    #[arg(long, default_value_t = FeatureParams::default().epsilon)]
    epsilon: f64,
    /// Smoothing radius: first delta (d).
    #[arg(long, default_value_t = FeatureParams::default().delta)]
    delta: f64,
    /// Smoothing radius: largest delta (d).
    #[arg(long, default_value_t = FeatureParams::default().delta_max)]
    delta_max: f64,
    /// Correlation the smoothing neighbourhood must reach (paper: 0.6).
    #[arg(long, default_value_t = FeatureParams::default().rho)]
    rho: f64,
    /// Polyline growth radius gamma_max (d).
    #[arg(long, default_value_t = FeatureParams::default().gamma_max)]
    gamma_max: f64,
    /// Connection cone length, in gamma_max.
    #[arg(long, default_value_t = FeatureParams::default().cone_length)]
    cone_length: f64,
    /// Connection cone half-angle mu, degrees (default 30).
    #[arg(long)]
    cone_angle: Option<f64>,
    /// Relaxation passes (paper: 1-2).
    #[arg(long, default_value_t = FeatureParams::default().relax_passes)]
    relax: usize,
    /// Across-line refinement of the line vertices: radius (d; 0 = off, the paper's growth points as they are).
    #[arg(long, default_value_t = FeatureParams::default().refine)]
    refine: f64,
    /// Across-line refinement: width of the strip around the line (d).
    #[arg(long, default_value_t = FeatureParams::default().refine_width)]
    refine_width: f64,
    /// Line vertices moved onto the maximum of the curvature profile across the line: half-width of the profile, in curvature fit radii (0 = off).
    #[arg(long, default_value_t = FeatureParams::default().crest)]
    crest: f64,
    /// Side of the cells polylines grow in (d).
    #[arg(long, default_value_t = FeatureParams::default().cell)]
    cell: f64,
    /// Feature points kept only where the curvature peaks across the line: the drop a crest must reach over 2.5 fit radii, in units of the curvature the fit noise makes (0 = off: the paper's whole band above alpha).
    #[arg(long, default_value_t = FeatureParams::default().peak)]
    peak: f64,
}

impl FeaturesArgs {
    fn params(&self) -> Result<FeatureParams> {
        let t = &self.thresholds;
        let d = FeatureParams::default();
        let p = FeatureParams {
            curvature: self.fit.params()?,
            alpha: t.alpha,
            phi: t.phi,
            growth_radius: t.growth_radius,
            epsilon: t.epsilon,
            delta: t.delta,
            delta_max: t.delta_max,
            rho: t.rho,
            gamma_max: t.gamma_max,
            cone_length: t.cone_length,
            cone_angle: t.cone_angle.map_or(d.cone_angle, f64::to_radians),
            relax_passes: t.relax,
            refine: t.refine,
            refine_width: t.refine_width,
            crest: t.crest,
            cell: t.cell,
            peak: t.peak,
            ..d
        };
        if let Err(e) = p.validate() {
            bail!("{e}");
        }
        Ok(p)
    }
}

pub fn run(a: FeaturesArgs) -> Result<()> {
    let s = a.common.settings_in(&a.run)?;
    s.no_keep("feature lines")?;
    let params = a.params()?;
    s.init_threads();
    super::check_distinct(&a.input, &a.output)?;
    let format = scanmesh::io::mesh_format(&a.output, a.ascii)?;
    let progress = super::progress::progress(s.quiet || a.json);
    let t0 = Instant::now();
    let mut run = s.open_input(&a.input, &a.output, params.cost(), progress.as_ref())?;
    let store = &mut run.ws.store;
    let (graph, report) = extract_lines(store, &params, run.opts, progress.as_ref())?;
    graph
        .write(&a.output, store.origin(), format)
        .with_context(|| format!("writing {}", a.output.display()))?;
    let secs = t0.elapsed().as_secs_f64();
    if a.json {
        outln!(
            "{}",
            serde_json::to_string_pretty(&summary(&report, secs, &a.output))?
        )?;
    } else {
        print_summary(&report, secs, &a.output);
    }
    Ok(())
}

fn summary(r: &FeaturesReport, secs: f64, out: &Path) -> serde_json::Value {
    let c = &r.counts;
    let kind = |k: usize| {
        serde_json::json!({
            "candidates": c.candidates[k],
            "enhanced": c.enhanced[k],
            "feature_points": c.smoothed[k],
            "corners": c.corners[k],
        })
    };
    serde_json::json!({
        "points": r.points,
        "tiles": r.tiles,
        "reloaded_tiles": r.run.retries,
        "spacing_d": r.curvature.spacing,
        "alpha": r.params.alpha,
        "ridge": kind(0),
        "valley": kind(1),
        "polylines": r.polylines,
        "corners": r.corners,
        "total_length": r.length,
        "mls_residual_max": r.curvature.max_error,
        "mls_residual_rms": r.curvature.rms,
        "curvature_reused": !r.computed_curvature,
        "seconds": secs,
        "seconds_curvature": r.curvature_secs,
        "seconds_lines": r.lines_secs,
        "peak_rss": super::peak(),
        "output": out.display().to_string(),
    })
}

fn print_summary(r: &FeaturesReport, secs: f64, out: &Path) {
    let c = &r.counts;
    super::report::summary(format!(
        "features: {} points, {} tiles ({} reloaded), d {:.4e}, alpha {:.4e}, feature points {} ridge / {} valley \
         (of {} / {} candidates), {} polylines, {} corners, length {:.4e}, MLS residual RMS {:.4e} max {:.4e}, \
         {:.2} s (curvature {:.2} s, lines {:.2} s), peak {} -> {}",
        r.points,
        r.tiles,
        r.run.retries,
        r.curvature.spacing,
        r.params.alpha,
        c.smoothed[0],
        c.smoothed[1],
        c.candidates[0],
        c.candidates[1],
        r.polylines,
        r.corners,
        r.length,
        r.curvature.rms,
        r.curvature.max_error,
        secs,
        r.curvature_secs,
        r.lines_secs,
        super::peak(),
        out.display()
    ));
}
