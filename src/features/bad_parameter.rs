//! Why feature or curvature parameters cannot be used: the typed field of
//! [`FeaturesError::BadParameter`](super::FeaturesError::BadParameter).

use super::HoodChoice;
use std::path::PathBuf;

/// A parameter of the feature or curvature passes that is out of range,
/// with its value.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum BadFeatureParameter {
    /// A length, angle or threshold that must be positive and finite.
    NotPositive {
        /// The parameter, in words ("growth radius").
        name: &'static str,
        /// The value given.
        value: f64,
    },
    /// A width or weight that must be finite and at least 0.
    Negative {
        /// The parameter, in words ("crest width").
        name: &'static str,
        /// The value given.
        value: f64,
    },
    /// The delta growth is not above 1.
    DeltaGrowth,
    /// The largest delta is below delta.
    DeltaMax,
    /// Rho is outside `[0, 1)`.
    Rho,
    /// The sector angle is not below pi/2.
    Sector,
    /// The cone half-angle is not below pi/2.
    ConeAngle,
    /// A quadratic curve is asked to fit fewer than 3 points.
    CurvePoints,
    /// The curvature neighbourhood is an unusable radius or too small a `k`.
    Hood {
        /// The neighbourhood given.
        hood: HoodChoice,
        /// The smallest `k`.
        min_k: usize,
    },
    /// Every point of the store coincides with its neighbours.
    Coincident {
        /// The store's directory.
        store: PathBuf,
        /// The mean spacing measured.
        spacing: f64,
    },
}

impl std::fmt::Display for BadFeatureParameter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        use BadFeatureParameter as B;
        match self {
            B::NotPositive { name, value } => {
                write!(f, "{name} must be positive and finite, not {value}")
            }
            B::Negative { name, value } => write!(f, "{name} must be finite and >= 0, not {value}"),
            B::DeltaGrowth => f.write_str("delta growth must be above 1"),
            B::DeltaMax => f.write_str("delta max must be at least delta"),
            B::Rho => f.write_str("rho must lie in [0, 1)"),
            B::Sector => f.write_str("the sector angle must be below pi/2"),
            B::ConeAngle => f.write_str("the cone half-angle must be below pi/2"),
            B::CurvePoints => f.write_str("a quadratic curve needs at least 3 points"),
            B::Hood { hood, min_k } => write!(
                f,
                "curvature neighbourhood {hood:?}: a radius must be positive, k at least {min_k}"
            ),
            B::Coincident { store, spacing } => write!(
                f,
                "{}: every point coincides with its neighbours (mean spacing {spacing}): no curvature",
                store.display()
            ),
        }
    }
}
