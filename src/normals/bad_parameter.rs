//! Why normal parameters cannot give normals: the typed field of
//! [`NormalsError::BadParameter`](super::NormalsError::BadParameter).

use glam::DVec3;

/// A parameter of the normals that cannot give normals, with its value.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum BadNormalParameter {
    /// `k` is below the 3 neighbours a tangent plane needs.
    TooFewNeighbours {
        /// The `k` given.
        k: usize,
    },
    /// The viewpoint is not a finite position.
    Viewpoint(DVec3),
    /// `tau` is not a bound on `|ni.nj|` in `[0, 1]`.
    Tau(f64),
    /// The single source's direction is not finite, or zero.
    Direction(DVec3),
    /// Orientation toward the scan stations of an input that names none.
    NoStations,
    /// A sensor hint with another orientation than the automatic one.
    SensorNotAuto,
    /// Orientation toward a viewpoint, with no viewpoint given.
    NoViewpoint,
    /// A viewpoint with an orientation that does not go toward it.
    ViewpointNotAsked,
}

impl std::fmt::Display for BadNormalParameter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            BadNormalParameter::TooFewNeighbours { k } => {
                write!(f, "k = {k}: a tangent plane needs at least 3 neighbours")
            }
            BadNormalParameter::Viewpoint(v) => {
                write!(f, "the viewpoint {v} is not a finite position")
            }
            BadNormalParameter::Tau(tau) => {
                write!(f, "tau = {tau} is not a bound on |ni.nj| in [0, 1]")
            }
            BadNormalParameter::Direction(d) => {
                write!(f, "the source direction {d} is not a direction")
            }
            BadNormalParameter::NoStations => f.write_str(
                "orientation toward the scan stations, but the input names no station \
                 (E57 scan poses give them)",
            ),
            BadNormalParameter::SensorNotAuto => {
                f.write_str("a sensor hint goes with the automatic orientation only")
            }
            BadNormalParameter::NoViewpoint => {
                f.write_str("orientation toward a viewpoint, but no viewpoint is given")
            }
            BadNormalParameter::ViewpointNotAsked => f.write_str(
                "a viewpoint goes with the orientation toward it (or the automatic one) only",
            ),
        }
    }
}
