//! Valley-ridge feature lines from point sets (paper 5: Pang, Pang, Xiao,
//! Acta Automatica Sinica 2010; `papers/README.md` section 5).
//!
//! - Curvature (section 2, [`curvature`]): per point, the quadratic height
//!   function over the PCA frame of the neighbourhood within `r = 2..4 d`
//!   (`d` the mean distance to the 6 nearest neighbours, `spacing`), its
//!   principal, mean and Gaussian curvatures and MLS residual. A tile
//!   kernel, per-point local: tiled equals untiled bit for bit. Results land
//!   in the store columns [`CURVATURE`] and [`CURVATURE_FLAGS`].
//!
//! Flags of a point's curvature (a bit set means the values it names are
//! not available, and they are NaN, never made up).

mod bad_parameter;
pub(crate) mod cost;
pub(crate) mod crest;
pub mod curvature;
pub(crate) mod curve;
pub(crate) mod enhance;
pub mod export;
pub mod extract;
pub(crate) mod hood;
pub(crate) mod kernel;
pub(crate) mod lift;
pub mod line_files;
pub mod lines;
pub mod params;
pub(crate) mod peak;
pub(crate) mod polyline;
pub(crate) mod quadric;
pub(crate) mod refine;
pub(crate) mod repair;
pub mod score;
pub(crate) mod seams;
pub(crate) mod smooth;
pub(crate) mod spacing;
pub(crate) mod stages;
pub(crate) mod stats;
mod summary;

pub use bad_parameter::BadFeatureParameter;
pub use curvature::{compute_curvature, CurvatureReport, CurvatureStage};

use crate::normals::{NormalParams, Orientation};
use crate::pipeline::PipelineError;
use crate::store::{ColumnSpec, Item, StoreError};
use serde::{Deserialize, Serialize};

/// Fewer than [`quadric::MIN_FIT_POINTS`] points in the neighbourhood: no
/// curvature.
pub(crate) const FLAG_SPARSE: u8 = 1;
/// The neighbourhood's PCA frame is undetermined (colinear, coincident): no
/// curvature.
pub(crate) const FLAG_DEGENERATE: u8 = 2;
/// The neighbourhood does not span the `(u, v)` plane well enough for a
/// quadratic (a pivot of the 6x6 solve vanished): no curvature.
pub(crate) const FLAG_ILL_CONDITIONED: u8 = 4;
/// The point has no oriented normal: `K` and the residual are given, `H`,
/// `k1`, `k2` (whose signs need the outside) are NaN.
pub(crate) const FLAG_UNORIENTED: u8 = 8;

/// Per-point curvature column: `k1, k2, H, K, residual` as f32.
pub const CURVATURE: ColumnSpec = ColumnSpec::new("curvature.f32", Item::F32(curvature::VALUES));
/// Per-point curvature flags (u8).
pub const CURVATURE_FLAGS: ColumnSpec = ColumnSpec::new("curvature_flags.u8", Item::U8);
/// The parameters and statistics that produced the curvature column (JSON).
pub(crate) const CURVATURE_META_FILE: &str = "curvature.json";

/// Which neighbourhood the quadratic is fitted to.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum CurvatureHood {
    /// Every point within this distance (absolute).
    Radius(f64),
    /// The k nearest points.
    Knn(usize),
    /// Paper 3's topological neighbours, k per query.
    Topological {
        /// Neighbours per query.
        k: usize,
        /// Cap on the mean reverse shift's iterations per point.
        max_iterations: usize,
    },
}

/// As the summary line says it: `radius 3.2008e-2`, `12 nearest`,
/// `12 topological neighbours`.
impl std::fmt::Display for CurvatureHood {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CurvatureHood::Radius(r) => write!(f, "radius {r:.4e}"),
            CurvatureHood::Knn(k) => write!(f, "{k} nearest"),
            CurvatureHood::Topological { k, .. } => write!(f, "{k} topological neighbours"),
        }
    }
}

/// How the neighbourhood is chosen, before the data's spacing is known.
#[derive(Clone, Copy, Debug, PartialEq, Default, Serialize, Deserialize)]
pub enum HoodChoice {
    /// The default: a radius of 3 mean spacings `d`, more on noisy input
    /// (`noise_adaptive_radius`).
    #[default]
    Auto,
    /// Radius in units of the mean spacing `d` (paper: 2..4; its dragon 2.8).
    Radius {
        /// The radius, in mean spacings.
        spacings: f64,
    },
    /// The k nearest points.
    Knn {
        /// Neighbours per point.
        k: usize,
    },
    /// Paper 3's topological neighbours, k per query.
    Topological {
        /// Neighbours per query.
        k: usize,
        /// Cap on the mean reverse shift's iterations per point.
        max_iterations: usize,
    },
}

/// Default curvature radius in mean spacings (on clean input).
pub(crate) const DEFAULT_RADIUS_SPACINGS: f64 = 3.0;

/// The default radius in mean spacings for a cloud whose tangent-plane
/// noise estimate (the normals pass's `2 x` median plane residual) is
/// `noise_ratio` nearest-neighbour distances: 3 up to a ratio of 0.25 (clean
/// scans and meshes measure 0.16-0.22: the planes' residual is curvature),
/// then 2 more per unit of ratio, at most 4.5. The paper widens its fits
/// with noise too (its Table 1: 1.8-2.8 d clean, 2.6-3.5 d at noise 1.0 d).
/// Measured on the wavy sheet at noise 0.5 sp (ratio 0.73, so r = 3.95 d):
/// recall/precision 78/74 % at 3 d, 92/91 % at 4 d.
pub(crate) fn noise_adaptive_radius(noise_ratio: f64) -> f64 {
    let extra = if noise_ratio.is_finite() {
        (2.0 * (noise_ratio - 0.25)).clamp(0.0, 1.5)
    } else {
        0.0
    };
    DEFAULT_RADIUS_SPACINGS + extra
}

impl HoodChoice {
    /// The neighbourhood for a cloud of mean spacing `d` whose normals pass
    /// measured `noise_ratio` (see [`noise_adaptive_radius`]).
    pub(crate) fn resolve(&self, d: f64, noise_ratio: f64) -> CurvatureHood {
        match *self {
            HoodChoice::Auto => CurvatureHood::Radius(noise_adaptive_radius(noise_ratio) * d),
            HoodChoice::Radius { spacings } => CurvatureHood::Radius(spacings * d),
            HoodChoice::Knn { k } => CurvatureHood::Knn(k),
            HoodChoice::Topological { k, max_iterations } => {
                CurvatureHood::Topological { k, max_iterations }
            }
        }
    }

    /// Refuses a radius that is not positive and finite, or a k too small for a quadric fit.
    pub fn validate(&self) -> Result<(), FeaturesError> {
        let ok = match *self {
            HoodChoice::Auto => true,
            HoodChoice::Radius { spacings } => spacings.is_finite() && spacings > 0.0,
            HoodChoice::Knn { k } | HoodChoice::Topological { k, .. } => {
                k + 1 >= quadric::MIN_FIT_POINTS
            }
        };
        if ok {
            Ok(())
        } else {
            Err(FeaturesError::BadParameter(BadFeatureParameter::Hood {
                hood: *self,
                min_k: quadric::MIN_FIT_POINTS - 1,
            }))
        }
    }
}

/// A fit's neighbourhood by kind (the CLI's `--neighbours`), its settings
/// given beside it ([`CurvatureParams::fit`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum FitHood {
    /// [`HoodChoice::Radius`], or [`HoodChoice::Auto`] without a radius.
    #[value(help = None::<&str>)]
    Radius,
    /// [`HoodChoice::Knn`].
    #[value(help = None::<&str>)]
    Knn,
    /// [`HoodChoice::Topological`].
    #[value(help = None::<&str>)]
    Topological,
}

/// How a fit's normals get their sign when the store has none (the CLI's
/// `--orient` of `curvature` and `features`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum FitOrientation {
    /// [`Orientation::SpanningTree`], the project's default.
    #[value(
        name = "mst",
        help = "Minimum spanning tree (paper 1), the project's default"
    )]
    SpanningTree,
    /// [`Orientation::SixSources`] with the default `tau`.
    #[value(name = "sources", help = "Paper 5's six sources")]
    SixSources,
}

/// Parameters of the curvature pass.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct CurvatureParams {
    /// Which neighbourhood the quadrics are fitted to.
    pub hood: HoodChoice,
    /// Normals to compute first when the store has none.
    pub normals: NormalParams,
}

impl CurvatureParams {
    /// The fit to a neighbourhood of kind `hood` (`radius`: its radius in
    /// mean spacings, else the noise-adaptive default; `k` and
    /// `max_iterations` for the kinds that take them), its normals signed
    /// by `orient` when the store has none; a neighbourhood that cannot be
    /// is refused.
    pub fn fit(
        hood: FitHood,
        radius: Option<f64>,
        k: usize,
        max_iterations: usize,
        orient: FitOrientation,
    ) -> Result<Self, FeaturesError> {
        let hood = match hood {
            FitHood::Radius => match radius {
                Some(spacings) => HoodChoice::Radius { spacings },
                None => HoodChoice::Auto,
            },
            FitHood::Knn => HoodChoice::Knn { k },
            FitHood::Topological => HoodChoice::Topological { k, max_iterations },
        };
        hood.validate()?;
        let orientation = match orient {
            FitOrientation::SpanningTree => Orientation::SpanningTree,
            FitOrientation::SixSources => Orientation::SixSources {
                tau: crate::normals::sources::DEFAULT_TAU,
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

    /// Refuses an unusable neighbourhood, or normal parameters that cannot
    /// give normals.
    pub fn validate(&self) -> Result<(), FeaturesError> {
        self.hood.validate()?;
        Ok(self.normals.validate()?)
    }
}

/// Errors of the curvature and feature-line passes.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum FeaturesError {
    /// Reading or writing the store failed.
    #[error(transparent)]
    Store(#[from] StoreError),
    /// The tile pipeline failed.
    #[error(transparent)]
    Pipeline(#[from] PipelineError),
    /// Computing the normals first failed.
    #[error(transparent)]
    Normals(#[from] crate::normals::NormalsError),
    /// Writing an output failed.
    #[error(transparent)]
    Io(#[from] crate::io::IoError),
    /// A parameter is out of range; the message says which and why.
    #[error("{0}")]
    BadParameter(BadFeatureParameter),
    /// The curvature metadata beside the store cannot be written.
    #[error("{path}: {source}")]
    Meta {
        /// The metadata file.
        path: std::path::PathBuf,
        /// Why it cannot be written (the encoder's or the system's error).
        #[source]
        source: Box<dyn std::error::Error + Send + Sync>,
    },
}
