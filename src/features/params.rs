//! The feature-line thresholds (paper 5 sections 2-5) and their defaults
//! from the data: every length in units of the mean spacing `d`, the
//! curvature threshold from the curvature distribution and the fit
//! residuals, so `features` works untuned; every one can be overridden.

use super::crest::Slab;
use super::curvature::CurvatureMeta;
use super::peak::{PeakTest, BAND_SPACINGS, DEFAULT_CONTRAST, WIDE_RADII};
use super::{
    BadFeatureParameter, CurvatureHood, CurvatureParams, FeaturesError, DEFAULT_RADIUS_SPACINGS,
};
use std::f64::consts::PI;
use BadFeatureParameter as B;

/// User-facing parameters; lengths in mean spacings `d`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FeatureParams {
    /// The curvature pass (and the normals it computes first when the store has none).
    pub curvature: CurvatureParams,
    /// Curvature threshold `alpha` (absolute, 1 / length); default
    /// `default_alpha`.
    pub alpha: Option<f64>,
    /// Enhancement radius `phi` (section 3).
    pub phi: f64,
    /// Growth-circle radius `R` (section 3).
    pub growth_radius: f64,
    /// Growth-circle sector angle (paper: pi/3).
    pub sector: f64,
    /// Fewest points a curve-fitting set keeps (section 3: sets with too
    /// few points are dropped).
    pub min_curve_points: usize,
    /// Corners closer than `epsilon` merge (section 3).
    pub epsilon: f64,
    /// Smoothing radius: start, growth factor, limit (section 4).
    pub delta: f64,
    /// Growth factor of the smoothing radius.
    pub delta_growth: f64,
    /// Largest smoothing radius.
    pub delta_max: f64,
    /// Correlation the smoothing neighbourhood must reach (paper: 0.6).
    pub rho: f64,
    /// Polyline growth radius `gamma_max` (section 5).
    pub gamma_max: f64,
    /// Connection cone: length in `gamma_max` (the paper's `alpha`),
    /// half-angle `mu` in radians.
    pub cone_length: f64,
    /// Half-angle `mu` of the connection cone, radians.
    pub cone_angle: f64,
    /// Relaxation passes (paper: 1-2).
    pub relax_passes: usize,
    /// Across-line refinement of the polyline vertices (`refine.rs`):
    /// radius (0: off) and width, in `d`. 10 d measured best of 5, 7.5,
    /// 10 (100k points, seed 1, noise 0.1 sp, ridge recall: stepped block
    /// 94.2 / 94.5 / 95.4 %, wavy sheet 93.6 / 93.3 / 93.3 %).
    pub refine: f64,
    /// Width of the across-line refinement, in `d`.
    pub refine_width: f64,
    /// Line vertices moved onto the crest of the curvature profile across
    /// the line (`crest.rs`): the half-width of the profile's slab, in
    /// curvature fit radii (0: off); its half-length is one fit radius.
    pub crest: f64,
    /// Side of the lattice cells polylines grow in (see `super::kernel`).
    pub cell: f64,
    /// Feature points kept only where the curvature peaks across the line
    /// (`peak.rs`): the drop a crest must reach, in units of the noise
    /// curvature `sigma / r^2` (0: off, the paper's band of `|k_i| > alpha`).
    pub peak: f64,
}

impl Default for FeatureParams {
    fn default() -> Self {
        FeatureParams {
            curvature: CurvatureParams::default(),
            alpha: None,
            phi: 4.5,
            growth_radius: 3.5,
            sector: PI / 3.0,
            min_curve_points: 5,
            epsilon: 2.0,
            delta: 4.0,
            delta_growth: 1.25,
            delta_max: 8.0,
            rho: 0.6,
            gamma_max: 2.5,
            // 4: lines broken by gaps of 8 d (a corrugated sheet whose crests are
            // 38 sp apart: 42 polylines for 34 lines at 3, 35 at 4); the creases
            // gained 0.5-1 % recall.
            cone_length: 4.0,
            cone_angle: PI / 6.0,
            relax_passes: 2,
            refine: 10.0,
            refine_width: 2.5,
            crest: 1.5,
            // 16 d: the tiles' margin holds a cell beyond the core, and
            // 32 d made the margin (75 d) four times a 256 MiB plan's
            // tile at 10M points; the synthetic figures are the same at
            // 16 d (within 0.4 %) as at 32 d.
            cell: 16.0,
            peak: DEFAULT_CONTRAST,
        }
    }
}

/// Thresholds in absolute units, for one cloud.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Resolved {
    /// Curvature threshold `alpha` (1 / length).
    pub alpha: f64,
    /// Enhancement radius `phi`.
    pub phi: f64,
    /// Growth-circle radius `R`.
    pub growth_radius: f64,
    /// Growth-circle sector angle, radians.
    pub sector: f64,
    /// Fewest points a curve-fitting set keeps.
    pub min_curve_points: usize,
    /// Distance below which corners merge.
    pub epsilon: f64,
    /// First smoothing radius.
    pub delta: f64,
    /// Growth factor of the smoothing radius.
    pub delta_growth: f64,
    /// Largest smoothing radius.
    pub delta_max: f64,
    /// Correlation the smoothing neighbourhood must reach.
    pub rho: f64,
    /// Polyline growth radius `gamma_max`.
    pub gamma_max: f64,
    /// Connection cone length.
    pub cone_length: f64,
    /// Connection cone half-angle `mu`, radians.
    pub cone_angle: f64,
    /// Relaxation passes.
    pub relax_passes: usize,
    /// Across-line refinement radius (0: off).
    pub refine: f64,
    /// Across-line refinement width.
    pub refine_width: f64,
    /// The crest's slab (`crest.rs`), absolute; `None` when off.
    pub crest: Option<Slab>,
    /// Side of the lattice cells polylines grow in.
    pub cell: f64,
    /// The crest test of the feature points (`peak.rs`); `None` when off.
    pub peak: Option<PeakTest>,
    /// The curvature neighbourhood, to recompute a feature point's quadric.
    pub hood: CurvatureHood,
    /// Mean spacing `d`.
    pub spacing: f64,
}

/// Multiple of the noise-induced curvature scale `sigma / r^2` the default
/// threshold stays above.
pub(crate) const NOISE_FACTOR: f64 = 8.0;
/// Share of the points the default threshold leaves below it at least.
pub(crate) const QUANTILE: f64 = 0.7;

/// The smallest drop a crest must reach, as a share of `alpha`: on a
/// noiseless cloud the noise curvature is zero, and a constant field
/// (a sphere's) would pass the crest test on rounding alone.
pub(crate) const PEAK_FLOOR: f64 = 0.02;

/// The default `alpha`: the larger of the 70th percentile of `|k_i|` (the
/// paper's dragon kept 30 % of its points) and eight times the curvature
/// that fit noise alone produces, `sigma / r^2` with `sigma` the median fit
/// residual (on crease models most points are flat and the percentile falls
/// into the noise).
pub(crate) fn default_alpha(meta: &CurvatureMeta) -> f64 {
    let r = match meta.resolved {
        CurvatureHood::Radius(r) => r,
        // The k nearest hold about as many points as the default radius.
        _ => DEFAULT_RADIUS_SPACINGS * meta.spacing,
    };
    let noise = NOISE_FACTOR * meta.median_residual / (r * r);
    meta.dominant_quantile(QUANTILE).max(noise)
}

impl FeatureParams {
    /// Refuses a threshold that is not finite, or not positive where a length or count must be.
    pub fn validate(&self) -> Result<(), FeaturesError> {
        self.curvature.validate()?;
        let positive = [
            ("phi", self.phi),
            ("growth radius", self.growth_radius),
            ("sector", self.sector),
            ("epsilon", self.epsilon),
            ("delta", self.delta),
            ("delta max", self.delta_max),
            ("gamma max", self.gamma_max),
            ("cone length", self.cone_length),
            ("cone angle", self.cone_angle),
            ("cell", self.cell),
            ("refine width", self.refine_width),
        ];
        for (name, v) in positive {
            if !(v.is_finite() && v > 0.0) {
                return Err(bad(B::NotPositive { name, value: v }));
            }
        }
        if !(self.crest.is_finite() && self.crest >= 0.0) {
            return Err(bad(B::Negative {
                name: "crest width",
                value: self.crest,
            }));
        }
        if !(self.peak.is_finite() && self.peak >= 0.0) {
            return Err(bad(B::Negative {
                name: "peak contrast",
                value: self.peak,
            }));
        }
        if !(self.refine.is_finite() && self.refine >= 0.0) {
            return Err(bad(B::Negative {
                name: "refine radius",
                value: self.refine,
            }));
        }
        if let Some(a) = self.alpha {
            if !(a.is_finite() && a >= 0.0) {
                return Err(bad(B::Negative {
                    name: "alpha",
                    value: a,
                }));
            }
        }
        if !(self.delta_growth.is_finite() && self.delta_growth > 1.0) {
            return Err(bad(B::DeltaGrowth));
        }
        if self.delta_max < self.delta {
            return Err(bad(B::DeltaMax));
        }
        if !(0.0..1.0).contains(&self.rho) {
            return Err(bad(B::Rho));
        }
        if self.sector >= PI / 2.0 {
            return Err(bad(B::Sector));
        }
        if self.cone_angle >= PI / 2.0 {
            return Err(bad(B::ConeAngle));
        }
        if self.min_curve_points < 3 {
            return Err(bad(B::CurvePoints));
        }
        Ok(())
    }

    /// Absolute thresholds for a cloud with the curvature `meta`.
    pub(crate) fn resolve(&self, meta: &CurvatureMeta) -> Resolved {
        let d = meta.spacing;
        // The fit radius: the neighbourhood's, or for k nearest about as
        // far as the default radius.
        let fit = match meta.resolved {
            CurvatureHood::Radius(r) => r,
            _ => DEFAULT_RADIUS_SPACINGS * d,
        };
        let crest = (self.crest > 0.0).then_some(Slab {
            along: fit,
            across: self.crest * fit,
        });
        let alpha = self.alpha.unwrap_or_else(|| default_alpha(meta));
        let peak = (self.peak > 0.0).then(|| PeakTest {
            near: fit,
            wide: WIDE_RADII * fit,
            band: BAND_SPACINGS * d,
            contrast: (self.peak * meta.median_residual / (fit * fit)).max(PEAK_FLOOR * alpha),
        });
        Resolved {
            alpha,
            phi: self.phi * d,
            growth_radius: self.growth_radius * d,
            sector: self.sector,
            min_curve_points: self.min_curve_points,
            epsilon: self.epsilon * d,
            delta: self.delta * d,
            delta_growth: self.delta_growth,
            delta_max: self.delta_max * d,
            rho: self.rho,
            gamma_max: self.gamma_max * d,
            cone_length: self.cone_length * self.gamma_max * d,
            cone_angle: self.cone_angle,
            relax_passes: self.relax_passes,
            refine: self.refine * d,
            refine_width: self.refine_width * d,
            crest,
            cell: self.cell * d,
            peak,
            hood: meta.resolved,
            spacing: d,
        }
    }
}

fn bad(reason: BadFeatureParameter) -> FeaturesError {
    FeaturesError::BadParameter(reason)
}

impl Resolved {
    /// Cells of the smoothing's grid: the first radius, where most points
    /// settle, but wide enough that `delta_max` spans at most the 8 cells
    /// a grid query reaches (`spatial::ball`).
    pub(crate) fn smooth_cell(&self) -> f64 {
        self.delta.max(self.delta_max / 8.0)
    }

    /// How far the priority of a polyline seed looks for corners.
    pub(crate) fn corner_cap(&self) -> f64 {
        3.0 * self.gamma_max
    }

    /// Radius around a point that its quadric's neighbourhood needs, for a
    /// radius neighbourhood (0 for k nearest: checked per point).
    pub fn fit_radius(&self) -> f64 {
        match self.hood {
            CurvatureHood::Radius(r) => r,
            _ => 0.0,
        }
    }

    /// How far a smoothed point's value (and its seed priority) reaches
    /// from its source point beyond the enhancement's own reach: corner
    /// status (corners within `epsilon`, each within `phi` of its source),
    /// then smoothing (enhanced points within `delta_max`) and the corner
    /// distance (corners within the cap). See `kernel.rs`.
    pub(crate) fn chain(&self) -> f64 {
        let corner_status = 2.0 * self.phi + self.epsilon;
        corner_status + 2.0 * self.phi + self.delta_max + self.corner_cap()
    }
}
