//! Tangent-plane normals by PCA of a neighbourhood (paper 1 section 2.3,
//! formula (1)): the unit normal is the eigenvector of the smallest
//! eigenvalue of `CV = sum (p - o)(p - o)^T` over the neighbourhood, `o` its
//! centroid.
//!
//! The paper's tangent plane is constrained to pass through the sample `x_i`
//! itself (not Hoppe's centroid), but its normal is still formula (1)'s
//! eigenvector about the centroid, which is what we compute. Which point
//! anchors the plane (sample or centroid) is the signed-distance stage's
//! choice, not this one's; we report both the normal and the centroid.
//!
//! Precision (PITFALLS.md "Numerics"): everything is f64 and relative to the
//! sample, so UTM-scale coordinates (~5e5) lose nothing: the centroid is
//! summed from `p - x_i`, then the covariance from `(p - x_i) - o` in a second
//! pass.

use glam::DVec3;

use super::eigen::{canonical_sign, sym3_eigen};
use crate::spatial::Neighbour;

/// The two smallest eigenvalues closer than this fraction of the largest
/// leave the normal undetermined. Rounding perturbs an eigenvector by about
/// `f64::EPSILON * l2 / (l1 - l0)` radians, so this keeps that error under
/// ~1e-6 rad; it flags strips thinner than ~1e-5 of their length (variance
/// ratio 1e-10), i.e. colinear points up to rounding.
pub(crate) const COLINEAR_TOLERANCE: f64 = 1e-10;

/// A fitted tangent plane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlaneFit {
    /// Unit eigenvector of the smallest eigenvalue, canonical sign (its
    /// largest-magnitude component positive; the first axis on ties). Not
    /// oriented: orientation is a later stage's job.
    pub normal: DVec3,
    /// The neighbourhood's centroid, absolute coordinates.
    pub centroid: DVec3,
    /// Covariance eigenvalues, ascending.
    pub eigenvalues: [f64; 3],
}

impl PlaneFit {
    /// `l0 / (l0 + l1 + l2)`: 0 on a plane, at most 1/3 (isotropic).
    pub fn surface_variation(&self) -> f64 {
        let [l0, l1, l2] = self.eigenvalues;
        let sum = l0 + l1 + l2;
        if sum > 0.0 {
            (l0 / sum).max(0.0)
        } else {
            0.0
        }
    }
}

/// Why a neighbourhood has no tangent plane.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum Degenerate {
    /// Fewer than 3 points (an index outside `points` also counts as missing).
    #[error("fewer than 3 points")]
    TooFew,
    /// All points at one location.
    #[error("all points coincide")]
    Coincident,
    /// The two smallest eigenvalues agree within `COLINEAR_TOLERANCE` of
    /// the largest: points on a line, or an isotropic blob. Either way the
    /// normal is undetermined.
    #[error("normal undetermined (colinear or isotropic points)")]
    Colinear,
}

/// Fits the plane of the neighbourhood `{points[sample]} ∪ nbrs`. `nbrs`
/// should not contain `sample` itself (query with `exclude = Some(sample)`),
/// or it is counted twice.
pub fn fit_plane(
    points: &[DVec3],
    sample: usize,
    nbrs: &[Neighbour],
) -> Result<PlaneFit, Degenerate> {
    let anchor = *points.get(sample).ok_or(Degenerate::TooFew)?;
    if nbrs.iter().any(|n| n.index as usize >= points.len()) {
        return Err(Degenerate::TooFew);
    }
    let others = nbrs.iter().map(|n| points[n.index as usize]);
    fit(anchor, others, nbrs.len())
}

/// Fits the plane of `pts` (relative to `pts[0]` for precision).
pub fn fit_plane_points(pts: &[DVec3]) -> Result<PlaneFit, Degenerate> {
    let (&anchor, rest) = pts.split_first().ok_or(Degenerate::TooFew)?;
    fit(anchor, rest.iter().copied(), rest.len())
}

/// PCA of `anchor` plus the `count` points of `others`, all taken relative
/// to `anchor`.
fn fit<I>(anchor: DVec3, others: I, count: usize) -> Result<PlaneFit, Degenerate>
where
    I: Iterator<Item = DVec3> + Clone,
{
    let n = count + 1;
    if n < 3 {
        return Err(Degenerate::TooFew);
    }
    let offset = others.clone().fold(DVec3::ZERO, |s, p| s + (p - anchor)) / n as f64;
    let mut cv = covariance_term(-offset);
    for p in others {
        add(&mut cv, covariance_term((p - anchor) - offset));
    }
    let (eigenvalues, vectors) = sym3_eigen(symmetric(cv));
    let [l0, l1, l2] = eigenvalues;
    if l2 <= 0.0 {
        return Err(Degenerate::Coincident);
    }
    if l1 - l0 <= COLINEAR_TOLERANCE * l2 {
        return Err(Degenerate::Colinear);
    }
    Ok(PlaneFit {
        normal: canonical_sign(vectors[0].normalize()),
        centroid: anchor + offset,
        eigenvalues,
    })
}

/// The six distinct entries of `d d^T`: xx, yy, zz, xy, xz, yz.
fn covariance_term(d: DVec3) -> [f64; 6] {
    [
        d.x * d.x,
        d.y * d.y,
        d.z * d.z,
        d.x * d.y,
        d.x * d.z,
        d.y * d.z,
    ]
}

fn add(acc: &mut [f64; 6], t: [f64; 6]) {
    for (a, b) in acc.iter_mut().zip(t) {
        *a += b;
    }
}

fn symmetric([xx, yy, zz, xy, xz, yz]: [f64; 6]) -> [[f64; 3]; 3] {
    [[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]]
}
