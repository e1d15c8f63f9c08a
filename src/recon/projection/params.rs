//! Parameters of the local-projection triangulation, with defaults that need
//! no tuning: every length is relative to the *local* spacing of the points
//! involved, so one setting serves a uniform scan, a 20:1 density step and
//! terrain.

use crate::normals::{NormalHood, NormalParams};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProjectionParams {
    /// Neighbourhood of each vertex: the k nearest (paper 2 section 2.4,
    /// k in 6..15) or paper 3's topological neighbours.
    pub k: usize,
    pub neighbourhood: NormalHood,
    /// A point closer than this many local spacings to a point of smaller
    /// input id is left out (0 keeps every point); see `thin.rs`.
    pub thin: f64,
    /// Longest edge, in local spacings (the larger of its ends').
    pub max_edge: f64,
    /// Neighbours higher over the tangent plane than this angle, seen from
    /// the vertex, are not connected (another sheet, or a fold).
    pub max_elevation_deg: f64,
    /// Largest corner angle of a triangle.
    pub max_angle_deg: f64,
}

/// Default k: the middle of the paper's range. Measured on the 1M noisy
/// dragon (see the module docs of `recon::projection`).
pub const DEFAULT_K: usize = 12;

impl Default for ProjectionParams {
    fn default() -> Self {
        ProjectionParams {
            k: DEFAULT_K,
            neighbourhood: NormalHood::Knn,
            thin: 0.6,
            max_edge: 8.0,
            max_elevation_deg: 45.0,
            max_angle_deg: 170.0,
        }
    }
}

/// A parameter outside its range.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("--{name} {value}: {why}")]
pub struct BadParameter {
    pub name: &'static str,
    pub value: f64,
    pub why: &'static str,
}

impl ProjectionParams {
    /// Checks every field's range.
    pub fn validate(&self) -> Result<(), BadParameter> {
        let bad = |name, value, why| Err(BadParameter { name, value, why });
        if !(3..=64).contains(&self.k) {
            return bad("k", self.k as f64, "must be between 3 and 64");
        }
        if !(0.0..1.0).contains(&self.thin) {
            return bad("thin", self.thin, "must be in [0, 1) local spacings");
        }
        if !(self.max_edge.is_finite() && self.max_edge >= 1.0) {
            return bad(
                "max-edge",
                self.max_edge,
                "must be at least 1 local spacing",
            );
        }
        if !(0.0 < self.max_elevation_deg && self.max_elevation_deg < 90.0) {
            return bad(
                "max-elevation",
                self.max_elevation_deg,
                "must be in (0, 90) degrees",
            );
        }
        if !(60.0 < self.max_angle_deg && self.max_angle_deg < 180.0) {
            return bad(
                "max-angle",
                self.max_angle_deg,
                "must be in (60, 180) degrees",
            );
        }
        Ok(())
    }

    /// The neighbourhood as the normals module's parameters (same index).
    pub fn hood(&self) -> NormalParams {
        NormalParams {
            k: self.k,
            neighbourhood: self.neighbourhood,
            ..NormalParams::default()
        }
    }
}
