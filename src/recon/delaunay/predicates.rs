//! Exact geometric predicates of the 3-D Delaunay triangulation, with a
//! deterministic tie-break for cospherical and cocircular points.
//!
//! `orient3d` and `insphere` are Shewchuk's adaptive predicates from the
//! `robust` crate: a fast f64 determinant with an error bound, and the exact
//! expansion arithmetic only when the bound does not settle the sign.
//!
//! Ties are broken by symbolic perturbation (Devillers & Teillaud,
//! "Perturbations for Delaunay and weighted Delaunay 3D triangulations",
//! 2011, the scheme CGAL's `Delaunay_triangulation_3` uses): every point is
//! lifted by an infinitesimal that grows with its rank, here its input id
//! (so the result is the same whatever order or tiling produced it). When
//! the exact determinant is zero the sign is that of the leading non-zero
//! coefficient, an orientation of four (or, on a hull plane, three) points.
//!
//! Sign convention (Shewchuk's): `orient(a, b, c, d) > 0` when `d` lies
//! below the plane in which `a, b, c` turn counter-clockwise seen from
//! above. Every cell of the triangulation is stored with `orient > 0`.

use glam::DVec3;
use robust::Coord3D;

#[inline(always)]
fn c3(p: DVec3) -> Coord3D<f64> {
    Coord3D {
        x: p.x,
        y: p.y,
        z: p.z,
    }
}

/// Exact sign of the orientation determinant (see the module doc).
///
/// A semi-static filter first, as [`insphere`]'s: Shewchuk's
/// `orient3dfast` in f64 and CGAL's static error bound for
/// `Orientation_3`, `5.11e-15 * X * Y * Z` over the largest coordinate
/// difference per axis, taken 8 times; `robust::orient3d` (adaptive,
/// exact) when it does not settle the sign. `robust`'s own filter sums a
/// permanent first (measured: 4.3 % of the 1M dragon's triangulation time
/// in `robust::orient3d`).
#[inline]
pub fn orient(a: DVec3, b: DVec3, c: DVec3, d: DVec3) -> f64 {
    let (ad, bd, cd) = (a - d, b - d, c - d);
    let m = ad.abs().max(bd.abs()).max(cd.abs());
    let (lo, hi) = (m.min_element(), m.max_element());
    if lo > 1e-90 && hi < 1e90 {
        let det = ad.x * (bd.y * cd.z - bd.z * cd.y)
            + bd.x * (cd.y * ad.z - cd.z * ad.y)
            + cd.x * (ad.y * bd.z - ad.z * bd.y);
        let bound = ORIENT_FILTER * m.x * m.y * m.z;
        if det > bound || -det > bound {
            return det;
        }
    }
    robust::orient3d(c3(a), c3(b), c3(c), c3(d))
}

/// Error-bound constant of [`orient`]'s filter (see there).
const ORIENT_FILTER: f64 = 4.1e-14;

/// Exact in-sphere determinant: positive when `e` is strictly inside the
/// sphere through `a, b, c, d` (which must have `orient > 0`).
///
/// A semi-static filter first (the form of CGAL's static filter for
/// `Side_of_oriented_sphere_3`): Shewchuk's expansion of the determinant in
/// f64 and a bound on its rounding error from the largest coordinate
/// difference per axis, `C * X * Y * Z * M^2`. A forward error analysis
/// of the expansion (24 products of four entries, each at most
/// `X Y Z 3 M^2`, about 17 roundings deep) gives `C` of about 1.4e-13;
/// CGAL's generated bound is 1.25e-13; `INSPHERE_FILTER` takes 8 times
/// that. Cheaper than `robust`'s own filter, which sums a permanent as
/// large as the determinant; when the bound does not settle the sign,
/// `robust::insphere` (adaptive, exact) decides.
#[inline]
pub fn insphere(a: DVec3, b: DVec3, c: DVec3, d: DVec3, e: DVec3) -> f64 {
    let (ae, be, ce, de) = (a - e, b - e, c - e, d - e);
    let m = ae.abs().max(be.abs()).max(ce.abs()).max(de.abs());
    let (lo, hi) = (m.min_element(), m.max_element());
    if lo > 1e-58 && hi < 1e61 {
        let ab = ae.x * be.y - be.x * ae.y;
        let bc = be.x * ce.y - ce.x * be.y;
        let cd = ce.x * de.y - de.x * ce.y;
        let da = de.x * ae.y - ae.x * de.y;
        let ac = ae.x * ce.y - ce.x * ae.y;
        let bd = be.x * de.y - de.x * be.y;
        let abc = ae.z * bc - be.z * ac + ce.z * ab;
        let bcd = be.z * cd - ce.z * bd + de.z * bc;
        let cda = ce.z * da + de.z * ac + ae.z * cd;
        let dab = de.z * ab + ae.z * bd + be.z * da;
        let det = (de.length_squared() * abc - ce.length_squared() * dab)
            + (be.length_squared() * cda - ae.length_squared() * bcd);
        let bound = INSPHERE_FILTER * m.x * m.y * m.z * hi * hi;
        if det > bound || -det > bound {
            return det;
        }
    }
    robust::insphere(c3(a), c3(b), c3(c), c3(d), c3(e))
}

/// Error-bound constant of [`insphere`]'s filter (see there).
const INSPHERE_FILTER: f64 = 1e-12;

/// Whether `p` (rank `rp`) is inside the sphere of the positively oriented
/// cell `v` (ranks from `r`, read only on a tie: they are a cache miss
/// away in the hot loop), ties broken by the perturbation: the highest-ranked
/// of the five points decides. If it is `p`, `p` is outside; otherwise `p`
/// is inside when putting `p` in that vertex's place keeps the cell positive
/// (the coefficient of that vertex's lifting infinitesimal). Four vertices of
/// a cell are never coplanar, so the loop ends before its last step.
#[inline]
pub fn in_sphere_perturbed(v: [DVec3; 4], r: impl FnOnce() -> [u64; 4], p: DVec3, rp: u64) -> bool {
    let det = insphere(v[0], v[1], v[2], v[3], p);
    if det != 0.0 {
        return det > 0.0;
    }
    sphere_tie(v, r(), p, rp)
}

#[cold]
fn sphere_tie(v: [DVec3; 4], r: [u64; 4], p: DVec3, rp: u64) -> bool {
    let mut order = [0usize, 1, 2, 3, 4];
    let rank = |i: usize| if i == 4 { rp } else { r[i] };
    order.sort_unstable_by_key(|&i| std::cmp::Reverse(rank(i)));
    for &i in &order {
        if i == 4 {
            return false;
        }
        let mut w = v;
        w[i] = p;
        let o = orient(w[0], w[1], w[2], w[3]);
        if o != 0.0 {
            return o > 0.0;
        }
    }
    false
}

/// A point off the plane of `a, b, c` (which must not be collinear): `a`
/// moved along the axis nearest to the plane's normal, so the exact
/// orientation with it is never zero.
fn off_plane(a: DVec3, b: DVec3, c: DVec3) -> DVec3 {
    let n = (b - a).cross(c - a).abs();
    let axis = if n.x >= n.y && n.x >= n.z {
        0
    } else if n.y >= n.z {
        1
    } else {
        2
    };
    let mut w = a;
    w[axis] += 1.0 + a[axis].abs();
    w
}

/// Whether `p`, which lies exactly in the plane of the non-collinear face
/// `f`, is inside the face's circumcircle, ties broken by the same
/// perturbation as [`in_sphere_perturbed`] restricted to the plane (CGAL's
/// `coplanar_side_of_bounded_circle`). Exact: for a point of the plane,
/// "inside the circle" is "inside any sphere through the circle", here the
/// sphere through `f` and a point `w` off the plane; orientations within
/// the plane are compared with `f`'s through the same `w`.
pub fn in_circle_perturbed(f: [DVec3; 3], r: [u64; 3], p: DVec3, rp: u64) -> bool {
    let w = off_plane(f[0], f[1], f[2]);
    let reference = orient(f[0], f[1], f[2], w).signum();
    let det = insphere(f[0], f[1], f[2], w, p) * reference;
    if det != 0.0 {
        return det > 0.0;
    }
    let mut order = [0usize, 1, 2, 3];
    let rank = |i: usize| if i == 3 { rp } else { r[i] };
    order.sort_unstable_by_key(|&i| std::cmp::Reverse(rank(i)));
    for &i in &order {
        if i == 3 {
            return false;
        }
        let mut g = f;
        g[i] = p;
        let o = orient(g[0], g[1], g[2], w) * reference;
        if o != 0.0 {
            return o > 0.0;
        }
    }
    false
}

/// Whether three points are collinear, exactly (all three coordinate-plane
/// projections have zero area).
pub fn collinear(a: DVec3, b: DVec3, c: DVec3) -> bool {
    use robust::Coord;
    let o = |u: fn(DVec3) -> (f64, f64)| {
        let (p, q, s) = (u(a), u(b), u(c));
        robust::orient2d(
            Coord { x: p.0, y: p.1 },
            Coord { x: q.0, y: q.1 },
            Coord { x: s.0, y: s.1 },
        )
    };
    o(|p| (p.x, p.y)) == 0.0 && o(|p| (p.y, p.z)) == 0.0 && o(|p| (p.z, p.x)) == 0.0
}
