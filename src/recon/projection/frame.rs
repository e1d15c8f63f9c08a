//! The local 2-D frame of a vertex (paper 2 section 2.7) and the planar
//! predicates the vertex selection uses.
//!
//! Deviations:
//! - The paper's unit vector `a` orthogonal to `n` (formula (2)) divides by
//!   a normal component and vanishes for normals such as `(0, s, s)`; the
//!   basis here is Duff et al.'s branchless one ("Building an orthonormal
//!   basis, revisited", 2017; glam's `any_orthonormal_pair`), still with
//!   `b2 = n x b1` as in formula (4).
//! - Coordinates are taken relative to the vertex `v` rather than to the
//!   neighbourhood centroid: the plane is the same (through the centroid,
//!   section 2.5), so every projected difference is the same; only the 2-D
//!   origin moves to `v`, which is what the angular order around `v`
//!   (section 2.8) is measured from. Formula (7) is read as the projected
//!   point's coordinates (the README's correction of its typo).
//! - Angles are pseudo-angles (the "diamond angle", monotone in the true
//!   angle, no trigonometry): only their order and closeness are used.

use glam::{DVec2, DVec3};

/// A tangent plane at a vertex: its unit normal and in-plane axes.
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    pub origin: DVec3,
    pub n: DVec3,
    pub b1: DVec3,
    pub b2: DVec3,
}

impl Frame {
    /// The frame at `origin` with unit normal `n`; `b1 x b2 = n`.
    pub fn new(origin: DVec3, n: DVec3) -> Self {
        let (b1, b2) = n.any_orthonormal_pair();
        Frame { origin, n, b1, b2 }
    }

    /// In-plane coordinates of `p` (formulas (5)-(7)) and its signed height
    /// over the plane.
    pub fn project(&self, p: DVec3) -> (DVec2, f64) {
        let d = p - self.origin;
        (DVec2::new(d.dot(self.b1), d.dot(self.b2)), d.dot(self.n))
    }
}

pub use crate::geom::pseudo_angle;

/// `b - a` measured counter-clockwise, in `[0, 4)`.
pub fn ccw_from(a: f64, b: f64) -> f64 {
    let d = b - a;
    if d < 0.0 {
        d + 4.0
    } else {
        d
    }
}

/// Twice the signed area of `abc`: positive when counter-clockwise.
pub fn orient(a: DVec2, b: DVec2, c: DVec2) -> f64 {
    (b - a).perp_dot(c - a)
}

/// Whether segments `ab` and `cd` cross at a point interior to both (a
/// touch at an endpoint or a collinear overlap is not a crossing: the
/// callers test segments that may share endpoints).
pub fn segments_cross(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> bool {
    // The second pair only when the first straddles: most segments a
    // front check meets lie to one side (it runs 44M times on 1M points).
    orient(a, b, c) * orient(a, b, d) < 0.0 && orient(c, d, a) * orient(c, d, b) < 0.0
}

/// Whether `p` lies strictly inside the counter-clockwise triangle `abc`.
pub fn strictly_inside(p: DVec2, a: DVec2, b: DVec2, c: DVec2) -> bool {
    orient(a, b, p) > 0.0 && orient(b, c, p) > 0.0 && orient(c, a, p) > 0.0
}

/// Whether `d` lies strictly inside the circumcircle of the
/// counter-clockwise triangle `abc` (the determinant of Guibas-Stolfi,
/// relative to `d`).
#[cfg(test)]
pub fn in_circle(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> bool {
    let (a, b, c) = (a - d, b - d, c - d);
    let det = a.length_squared() * b.perp_dot(c) - b.length_squared() * a.perp_dot(c)
        + c.length_squared() * a.perp_dot(b);
    det > 0.0
}

/// Whether the open counter-clockwise angular intervals `(s1, s1 + w1)` and
/// `(s2, s2 + w2)` (pseudo-angles, widths below 2, i.e. below 180 degrees)
/// overlap.
pub fn arcs_overlap(s1: f64, w1: f64, s2: f64, w2: f64) -> bool {
    let d = ccw_from(s1, s2);
    d < w1 || ccw_from(s2, s1) < w2
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_is_right_handed_and_projects() {
        for n in [
            DVec3::Z,
            -DVec3::Z,
            DVec3::new(0.0, 1.0, 1.0).normalize(),
            DVec3::new(-0.3, 0.2, -0.9).normalize(),
        ] {
            let f = Frame::new(DVec3::ONE, n);
            assert!((f.b1.cross(f.b2) - n).length() < 1e-12);
            assert!((f.n.cross(f.b1) - f.b2).length() < 1e-12);
            let (q, h) = f.project(DVec3::ONE + 2.0 * f.b1 - f.b2 + 0.5 * n);
            assert!((q - DVec2::new(2.0, -1.0)).length() < 1e-12);
            assert!((h - 0.5).abs() < 1e-12);
        }
    }

    #[test]
    fn pseudo_angles_follow_the_angle() {
        let mut last = -1.0;
        for i in 0..360 {
            let a = (i as f64).to_radians();
            let p = pseudo_angle(DVec2::new(a.cos(), a.sin()));
            assert!(p > last && p < 4.0, "{i}: {p} after {last}");
            last = p;
        }
        assert_eq!(ccw_from(3.5, 0.5), 1.0);
        assert!(arcs_overlap(3.8, 0.5, 0.1, 0.5));
        assert!(!arcs_overlap(0.0, 0.5, 0.5, 0.5));
        assert!(arcs_overlap(1.0, 0.5, 1.0, 0.5));
    }

    #[test]
    fn planar_predicates() {
        let (a, b, c) = (DVec2::ZERO, DVec2::X, DVec2::Y);
        assert!(orient(a, b, c) > 0.0);
        assert!(strictly_inside(DVec2::splat(0.2), a, b, c));
        assert!(!strictly_inside(DVec2::new(0.5, 0.0), a, b, c));
        assert!(in_circle(a, b, c, DVec2::splat(0.9)));
        assert!(!in_circle(a, b, c, DVec2::splat(1.1)));
        assert!(segments_cross(a, DVec2::ONE, b, c));
        assert!(!segments_cross(a, b, b, c));
    }
}
