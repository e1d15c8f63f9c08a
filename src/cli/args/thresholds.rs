//! The feature lines' thresholds (`features`), all of paper 5's, and
//! their mapping onto [`FeatureParams`].

use anyhow::{bail, Result};
use clap::Args;
use scanmesh::features::params::FeatureParams;
use scanmesh::features::CurvatureParams;

/// Every threshold of paper 5, lengths in mean spacings d (defaults from
/// the data; see `features::params`).
#[derive(Args)]
pub struct Thresholds {
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

impl Thresholds {
    /// The feature parameters with these thresholds over `curvature`.
    pub fn params(&self, curvature: CurvatureParams) -> Result<FeatureParams> {
        let t = self;
        let d = FeatureParams::default();
        let p = FeatureParams {
            curvature,
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
