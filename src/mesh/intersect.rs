//! Exact triangle-triangle intersection for the self-intersection count of
//! `scanmesh eval`, with pairs that share vertices handled by what they
//! share (the combinatorial definition used by CGAL's
//! `Polygon_mesh_processing::self_intersections`: two triangles intersect
//! when they meet anywhere beyond the vertices and edge they share).
//!
//! Every decision is a sign of Shewchuk's orient3d / orient2d (the `robust`
//! crate: adaptive precision, exact for any f64 input), so the answer is
//! exact for the given coordinates; coplanar cases drop the coordinate of
//! the dominant normal axis, which is exact too.
//!
//! The general test rests on one fact: two closed triangles intersect iff
//! an edge of one meets the other. (Non-coplanar: the intersection is a
//! segment on the planes' common line whose ends lie on the triangles'
//! boundaries. Coplanar: overlapping triangles either cross edges or one
//! contains the other's edges.) So six exact segment-triangle tests decide
//! a pair, with no tolerance anywhere.

use glam::DVec3;
use robust::{orient2d, orient3d, Coord, Coord3D};

fn c3(p: DVec3) -> Coord3D<f64> {
    Coord3D {
        x: p.x,
        y: p.y,
        z: p.z,
    }
}

/// Sign of the volume of `abcd` (exact): zero iff coplanar.
fn orient(a: DVec3, b: DVec3, c: DVec3, d: DVec3) -> i8 {
    sign(orient3d(c3(a), c3(b), c3(c), c3(d)))
}

fn sign(x: f64) -> i8 {
    if x > 0.0 {
        1
    } else if x < 0.0 {
        -1
    } else {
        0
    }
}

/// Whether the three corners are collinear (exactly): such a triangle has
/// no plane, and the caller leaves it out of the count.
pub fn is_flat(t: &[DVec3; 3]) -> bool {
    let [x, y] = drop_axis(dominant_axis(t));
    let p = t.map(|v| Coord { x: v[x], y: v[y] });
    // A non-flat triangle is non-flat in the projection along its dominant
    // normal axis; a flat one is flat in every projection.
    orient2d(p[0], p[1], p[2]) == 0.0
}

/// Axis of the largest component of the (float) normal: projecting along
/// it keeps a non-degenerate triangle non-degenerate.
fn dominant_axis(t: &[DVec3; 3]) -> usize {
    let n = (t[1] - t[0]).cross(t[2] - t[0]).abs();
    if n.x >= n.y && n.x >= n.z {
        0
    } else if n.y >= n.z {
        1
    } else {
        2
    }
}

fn drop_axis(axis: usize) -> [usize; 2] {
    match axis {
        0 => [1, 2],
        1 => [2, 0],
        _ => [0, 1],
    }
}

/// Closed segment `ab` against closed triangle `t` (not flat).
pub fn segment_meets_triangle(a: DVec3, b: DVec3, t: &[DVec3; 3]) -> bool {
    let sa = orient(t[0], t[1], t[2], a);
    let sb = orient(t[0], t[1], t[2], b);
    if sa == sb && sa != 0 {
        return false;
    }
    if sa == 0 && sb == 0 {
        return coplanar_segment_meets_triangle(a, b, t);
    }
    // The line ab crosses the plane once, inside the segment; it passes
    // through the closed triangle iff it sees the three edges turning the
    // same way (zeros allowed: the crossing is on an edge or a corner).
    let s = [
        orient(a, b, t[0], t[1]),
        orient(a, b, t[1], t[2]),
        orient(a, b, t[2], t[0]),
    ];
    s.iter().all(|&x| x >= 0) || s.iter().all(|&x| x <= 0)
}

/// 2-D version, `a`, `b` in the plane of `t`.
fn coplanar_segment_meets_triangle(a: DVec3, b: DVec3, t: &[DVec3; 3]) -> bool {
    let [x, y] = drop_axis(dominant_axis(t));
    let p = |v: DVec3| Coord { x: v[x], y: v[y] };
    let (a, b) = (p(a), p(b));
    let t = t.map(p);
    if inside2(a, &t) || inside2(b, &t) {
        return true;
    }
    (0..3).any(|i| segments_meet2(a, b, t[i], t[(i + 1) % 3]))
}

fn orient2(a: Coord<f64>, b: Coord<f64>, c: Coord<f64>) -> i8 {
    sign(orient2d(a, b, c))
}

/// Closed point-in-triangle in 2-D (the triangle is not flat).
fn inside2(p: Coord<f64>, t: &[Coord<f64>; 3]) -> bool {
    let s = [
        orient2(t[0], t[1], p),
        orient2(t[1], t[2], p),
        orient2(t[2], t[0], p),
    ];
    s.iter().all(|&x| x >= 0) || s.iter().all(|&x| x <= 0)
}

/// Closed segments `ab` and `cd` meet, in 2-D.
pub(crate) fn segments_meet2(a: Coord<f64>, b: Coord<f64>, c: Coord<f64>, d: Coord<f64>) -> bool {
    let (d1, d2) = (orient2(a, b, c), orient2(a, b, d));
    let (d3, d4) = (orient2(c, d, a), orient2(c, d, b));
    if d1 * d2 < 0 && d3 * d4 < 0 {
        return true;
    }
    let on = |p: Coord<f64>, q: Coord<f64>, r: Coord<f64>| {
        p.x.min(q.x) <= r.x && r.x <= p.x.max(q.x) && p.y.min(q.y) <= r.y && r.y <= p.y.max(q.y)
    };
    (d1 == 0 && on(a, b, c))
        || (d2 == 0 && on(a, b, d))
        || (d3 == 0 && on(c, d, a))
        || (d4 == 0 && on(c, d, b))
}

/// Two triangles with no vertex in common meet anywhere.
fn disjoint_pair_meets(p: &[DVec3; 3], q: &[DVec3; 3]) -> bool {
    (0..3).any(|i| segment_meets_triangle(p[i], p[(i + 1) % 3], q))
        || (0..3).any(|i| segment_meets_triangle(q[i], q[(i + 1) % 3], p))
}

/// Whether triangles `p` and `q` (vertex indices `pi`, `qi`, positions
/// `p`, `q`, neither flat) intersect beyond what they share:
/// - nothing shared: any contact;
/// - one vertex `a` (p = abc, q = ade): segment bc meets q or de meets p
///   (the contact is a segment from `a` on the planes' common line, which
///   leaves through the far edge of the shorter side);
/// - an edge `ab` (p = abc, q = abd): `d` in p's plane on `c`'s side of
///   `ab` (the triangles fold onto each other);
/// - all three (a duplicate): always, they cover each other.
pub fn triangles_intersect(pi: [u32; 3], p: &[DVec3; 3], qi: [u32; 3], q: &[DVec3; 3]) -> bool {
    let shared: Vec<(usize, usize)> = (0..3)
        .flat_map(|i| (0..3).map(move |j| (i, j)))
        .filter(|&(i, j)| pi[i] == qi[j])
        .collect();
    match shared.as_slice() {
        [] => disjoint_pair_meets(p, q),
        &[(i, j)] => {
            let (b, c) = (p[(i + 1) % 3], p[(i + 2) % 3]);
            let (d, e) = (q[(j + 1) % 3], q[(j + 2) % 3]);
            segment_meets_triangle(b, c, q) || segment_meets_triangle(d, e, p)
        }
        &[(i0, j0), (i1, j1)] => {
            let c = p[3 - i0 - i1];
            let d = q[3 - j0 - j1];
            let (a, b) = (p[i0], p[i1]);
            folded(a, b, c, d)
        }
        _ => true,
    }
}

/// Triangles `abc` and `abd` overlap: coplanar with `c` and `d` on the
/// same side of `ab`.
fn folded(a: DVec3, b: DVec3, c: DVec3, d: DVec3) -> bool {
    if orient(a, b, c, d) != 0 {
        return false;
    }
    let [x, y] = drop_axis(dominant_axis(&[a, b, c]));
    let p = |v: DVec3| Coord { x: v[x], y: v[y] };
    orient2(p(a), p(b), p(c)) == orient2(p(a), p(b), p(d))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(x: f64, y: f64, z: f64) -> DVec3 {
        DVec3::new(x, y, z)
    }

    #[test]
    fn crossing_and_separate_triangles() {
        let p = [v(0., 0., 0.), v(2., 0., 0.), v(0., 2., 0.)];
        let through = [v(0.5, 0.5, -1.), v(0.5, 0.5, 1.), v(3., 3., 0.5)];
        let above = [v(0.5, 0.5, 0.1), v(1.5, 0.5, 0.1), v(0.5, 1.5, 1.)];
        assert!(triangles_intersect([0, 1, 2], &p, [3, 4, 5], &through));
        assert!(!triangles_intersect([0, 1, 2], &p, [3, 4, 5], &above));
        // Touching at one point counts: p's corner lies on q.
        let touch = [
            v(0., 0., 0.) + v(-1., -1., 1.),
            v(1., 1., -1.),
            v(-1., 1., 0.),
        ];
        assert!(segment_meets_triangle(touch[0], touch[1], &p));
    }

    #[test]
    fn coplanar_pairs() {
        let p = [v(0., 0., 0.), v(2., 0., 0.), v(0., 2., 0.)];
        let inner = [v(0.2, 0.2, 0.), v(0.5, 0.2, 0.), v(0.2, 0.5, 0.)];
        let apart = [v(3., 3., 0.), v(4., 3., 0.), v(3., 4., 0.)];
        assert!(triangles_intersect([0, 1, 2], &p, [3, 4, 5], &inner));
        assert!(!triangles_intersect([0, 1, 2], &p, [3, 4, 5], &apart));
    }

    #[test]
    fn shared_vertex_and_edge() {
        let a = v(0., 0., 0.);
        let p = [a, v(2., 0., 0.), v(0., 2., 0.)];
        // A fan neighbour on the other side of the shared vertex: no contact.
        let q = [a, v(-1., 0., 0.), v(0., -1., 0.)];
        assert!(!triangles_intersect([0, 1, 2], &p, [0, 3, 4], &q));
        // Same vertex, reaching into p from above: its far edge crosses p.
        let r = [a, v(1., 0.5, 1.), v(0.5, 1., -1.)];
        assert!(triangles_intersect([0, 1, 2], &p, [0, 5, 6], &r));
        // Sharing the edge 0-1 on opposite sides (flat sheet): fine;
        // folded onto the same side: an intersection.
        let flat = [a, v(2., 0., 0.), v(1., -1., 0.)];
        let fold = [a, v(2., 0., 0.), v(1., 0.5, 0.)];
        let bent = [a, v(2., 0., 0.), v(1., 0.5, 0.3)];
        assert!(!triangles_intersect([0, 1, 2], &p, [0, 1, 7], &flat));
        assert!(triangles_intersect([0, 1, 2], &p, [0, 1, 7], &fold));
        assert!(!triangles_intersect([0, 1, 2], &p, [0, 1, 7], &bent));
        assert!(triangles_intersect([0, 1, 2], &p, [2, 0, 1], &p));
    }

    #[test]
    fn flat_triangles_are_recognised() {
        assert!(is_flat(&[v(0., 0., 0.), v(1., 1., 1.), v(2., 2., 2.)]));
        assert!(!is_flat(&[v(0., 0., 0.), v(1., 0., 0.), v(0., 0., 1.)]));
    }
}
