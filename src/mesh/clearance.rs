//! Whether two triangles of a mesh under construction meet, or come within
//! a slack of each other, beyond the vertices and edge they share.
//!
//! A kernel decides on coordinates rounded from the ones the mesh is
//! written with (f32 offsets from the store origin, against the input's own
//! f64), so an exact test on its coordinates can pass a pair that the
//! written mesh has touching: a depth camera's quantised points put a
//! vertex within 1e-7 of a neighbour's edge (`kinect_two_scans.e57`: 7
//! pairs). A pair that clears the exact test ([`super::intersect`]) by
//! less than the rounding's reach is refused too.
//!
//! The clearance of the parts not shared: no vertex shared, the least
//! distance from an edge of one triangle to the other; one vertex shared,
//! from the edge opposite it in each to the other triangle; an edge shared,
//! from the corner opposite it in each to the other triangle.

use super::closest::{point_triangle_distance2, segment_segment_distance2};
use super::intersect::triangles_intersect;
use glam::DVec3;

/// Whether triangles `pi` (corners `p`) and `qi` (corners `q`) meet beyond
/// what they share, or pass closer than `slack` there.
pub(crate) fn meet_within(
    pi: [u32; 3],
    p: &[DVec3; 3],
    qi: [u32; 3],
    q: &[DVec3; 3],
    slack: f64,
) -> bool {
    if slack > 0.0 && apart_by_planes(pi, p, qi, q, 2.0 * slack) {
        return false;
    }
    if triangles_intersect(pi, p, qi, q) {
        return true;
    }
    if slack <= 0.0 {
        return false;
    }
    let shared: Vec<(usize, usize)> = (0..3)
        .flat_map(|i| (0..3).map(move |j| (i, j)))
        .filter(|&(i, j)| pi[i] == qi[j])
        .collect();
    let s2 = slack * slack;
    match shared.as_slice() {
        [] => (0..3).any(|i| {
            segment_triangle_distance2(p[i], p[(i + 1) % 3], q) < s2
                || segment_triangle_distance2(q[i], q[(i + 1) % 3], p) < s2
        }),
        &[(i, j)] => {
            segment_triangle_distance2(p[(i + 1) % 3], p[(i + 2) % 3], q) < s2
                || segment_triangle_distance2(q[(j + 1) % 3], q[(j + 2) % 3], p) < s2
        }
        &[(i0, j0), (i1, j1)] => {
            let c = p[3 - i0 - i1];
            let d = q[3 - j0 - j1];
            point_triangle_distance2(c, q[0], q[1], q[2]) < s2
                || point_triangle_distance2(d, p[0], p[1], p[2]) < s2
        }
        _ => true,
    }
}

/// Whether each triangle's corners not shared lie more than `gap` beyond
/// the other along an axis of the other ([`beyond`]): then the two neither
/// meet beyond what they share nor come within `gap` there. The common
/// cases, neighbours on a curved surface and triangles of one fan, are
/// settled by a few dot products; `gap` is far above the float error of
/// the projections (it is taken at twice a positive slack).
fn apart_by_planes(pi: [u32; 3], p: &[DVec3; 3], qi: [u32; 3], q: &[DVec3; 3], gap: f64) -> bool {
    beyond(p, pi, q, qi, gap) && beyond(q, qi, p, pi, gap)
}

/// Whether the corners of `q` not in `pi` all project more than `gap`
/// past `p` on one of `p`'s axes (its normal, either way, or the outward
/// normal of an edge in its plane) at whose far end every shared corner
/// lies: `q` is the hull of those corners and the shared ones, so it then
/// keeps `gap` from `p` except at what they share.
fn beyond(p: &[DVec3; 3], pi: [u32; 3], q: &[DVec3; 3], qi: [u32; 3], gap: f64) -> bool {
    let n = (p[1] - p[0]).cross(p[2] - p[0]);
    let len = n.length();
    if len == 0.0 || !len.is_finite() {
        return false;
    }
    let n = n / len;
    let others = |k: &usize| !pi.contains(&qi[*k]);
    if !(0..3).any(|k| others(&k)) {
        return false;
    }
    let past = |axis: DVec3, at: DVec3| (0..3).filter(others).all(|k| axis.dot(q[k] - at) > gap);
    if past(n, p[0]) || past(-n, p[0]) {
        return true;
    }
    (0..3).any(|k| {
        let (a, b, c) = (p[k], p[(k + 1) % 3], p[(k + 2) % 3]);
        let shared_on_edge = (0..3)
            .filter(|&j| qi.contains(&pi[j]))
            .all(|j| j == k || j == (k + 1) % 3);
        let mut m = (b - a).cross(n).normalize_or_zero();
        if m.dot(c - a) > 0.0 {
            m = -m;
        }
        shared_on_edge && m != DVec3::ZERO && past(m, a)
    })
}

/// Squared distance from segment `ab` to triangle `t`, for a segment that
/// does not cross it: the nearer of its ends' distances and its distances
/// to the triangle's edges.
fn segment_triangle_distance2(a: DVec3, b: DVec3, t: &[DVec3; 3]) -> f64 {
    let ends = point_triangle_distance2(a, t[0], t[1], t[2])
        .min(point_triangle_distance2(b, t[0], t[1], t[2]));
    (0..3)
        .map(|k| segment_segment_distance2(a, b, t[k], t[(k + 1) % 3]))
        .fold(ends, f64::min)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(x: f64, y: f64, z: f64) -> DVec3 {
        DVec3::new(x, y, z)
    }

    /// A vertex 1e-7 off a neighbour's edge: apart for the exact test,
    /// touching within a slack of 1e-6, apart again at 1e-8.
    #[test]
    fn a_vertex_just_off_an_edge_is_within_the_slack() {
        let a = v(0., 0., 0.);
        let p = [a, v(2., 0., 0.), v(1., 2., 0.)];
        let q = [a, v(1., -1e-7, 0.), v(1., -2., 0.)];
        assert!(!triangles_intersect([0, 1, 2], &p, [0, 3, 4], &q));
        assert!(meet_within([0, 1, 2], &p, [0, 3, 4], &q, 1e-6));
        assert!(!meet_within([0, 1, 2], &p, [0, 3, 4], &q, 1e-8));
    }

    /// Neighbours across an edge, flat or bent, keep their clearance; a
    /// near fold (the far corner 1e-7 over the other triangle) does not.
    #[test]
    fn an_edge_shared_is_judged_by_the_far_corners() {
        let (a, b) = (v(0., 0., 0.), v(2., 0., 0.));
        let p = [a, b, v(1., 1., 0.)];
        let flat = [a, b, v(1., -1., 0.)];
        let bent = [a, b, v(1., -1., 0.5)];
        let fold = [a, b, v(1., 0.5, 1e-7)];
        assert!(!meet_within([0, 1, 2], &p, [0, 1, 3], &flat, 1e-6));
        assert!(!meet_within([0, 1, 2], &p, [0, 1, 3], &bent, 1e-6));
        assert!(meet_within([0, 1, 2], &p, [0, 1, 3], &fold, 1e-6));
        assert!(!meet_within([0, 1, 2], &p, [0, 1, 3], &fold, 0.0));
    }

    /// Neighbours on a curved surface are settled by their planes; the
    /// same triangle twice is not.
    #[test]
    fn planes_settle_bent_neighbours_but_not_a_repeat() {
        let (a, b) = (v(0., 0., 0.), v(2., 0., 0.));
        let p = [a, b, v(1., 1., 0.)];
        let bent = [a, b, v(1., -1., 0.5)];
        assert!(apart_by_planes([0, 1, 2], &p, [0, 1, 3], &bent, 1e-6));
        // Flat neighbours across an edge, and two triangles of a fan.
        let flat = [a, b, v(1., -1., 0.)];
        assert!(apart_by_planes([0, 1, 2], &p, [0, 1, 3], &flat, 1e-6));
        let fan = [a, v(-1., 1., 0.), v(-1., -0.5, 0.)];
        assert!(apart_by_planes([0, 1, 2], &p, [0, 4, 5], &fan, 1e-6));
        // A corner shared off the axis' edge proves nothing: q reaches
        // back into p from the corner opposite the edge.
        let into = [v(1., 1., 0.), v(3., -1., 0.), v(1., -3., 0.)];
        assert!(!apart_by_planes([0, 1, 2], &p, [2, 6, 7], &into, 1e-6));
        assert!(meet_within([0, 1, 2], &p, [2, 6, 7], &into, 1e-6));
        assert!(!apart_by_planes([0, 1, 2], &p, [0, 1, 2], &p, 1e-6));
        assert!(meet_within([0, 1, 2], &p, [2, 0, 1], &p, 1e-6));
    }

    /// Separate triangles: the least distance between their edges.
    #[test]
    fn separate_triangles_by_their_gap() {
        let p = [v(0., 0., 0.), v(2., 0., 0.), v(0., 2., 0.)];
        let q = [v(0.5, 0.5, 1e-7), v(3., 3., 1.), v(3., 0., 1.)];
        assert!(meet_within([0, 1, 2], &p, [3, 4, 5], &q, 1e-6));
        let far = q.map(|x| x + v(0., 0., 0.5));
        assert!(!meet_within([0, 1, 2], &p, [3, 4, 5], &far, 1e-6));
    }
}
