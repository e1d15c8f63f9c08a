//! What paper 4's selection reads of the triangulation around one vertex:
//! its *umbrella*, every Delaunay triangle through it, each with the far
//! vertices of its two cells (its apexes); the nearest-neighbour distances;
//! and whether a triangle is proven to belong to the whole cloud's
//! triangulation when only a tile's points were triangulated.
//!
//! The proof (the streaming-Delaunay rule, for triangles): the spheres
//! through a triangle's corners that hold none of the tile's points are the
//! pencil between its two cells' circumspheres. If one of them lies inside
//! the loaded region, where every point of the cloud was loaded, it holds no
//! point of the cloud at all, so the triangle is Delaunay in the cloud too.
//! The smallest such sphere is tried.

use super::triangulation::{Delaunay, INFINITE};
use crate::geom::Aabb;
use glam::DVec3;

/// A Delaunay triangle `(i, a, b)` seen from `i`: `a < b`, and the far
/// vertices of its two cells (either may be [`INFINITE`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Wing {
    pub a: u32,
    pub b: u32,
    pub apex: [u32; 2],
}

/// The umbrella of vertex `i`, appended to `out` (cleared first); `star`
/// is scratch. Wings come in no particular order (every reader takes all
/// of them), apexes in increasing order. Each triangle is read once, from
/// the lower-numbered of its two cells, with the other cell's apex read
/// across the shared face (sorting every cell's three triangles and
/// pairing them was 15 % of the run).
pub fn umbrella(d: &Delaunay, i: u32, star: &mut Vec<u32>, out: &mut Vec<Wing>) {
    out.clear();
    d.star(i, star);
    for &c in star.iter() {
        let cell = d.cell(c);
        let Some(s) = cell.v.iter().position(|&x| x == i) else {
            continue;
        };
        for k in 1..4 {
            // The face through `i` opposite corner `f`, shared with the
            // neighbour across it.
            let f = (s + k) & 3;
            let (next, face) = (cell.n[f] >> 2, (cell.n[f] & 3) as usize);
            if next < c {
                continue;
            }
            let mut rest = (0..4).filter(|&j| j != s && j != f).map(|j| cell.v[j]);
            let (Some(a), Some(b)) = (rest.next(), rest.next()) else {
                continue;
            };
            if a == INFINITE || b == INFINITE {
                continue;
            }
            let (w, z) = (cell.v[f], d.cell(next).v[face]);
            out.push(Wing {
                a: a.min(b),
                b: a.max(b),
                apex: [w.min(z), w.max(z)],
            });
        }
    }
}

/// Every vertex's nearest other vertex (a Delaunay neighbour, always;
/// ties: the smaller rank) and the distance to it, [`INFINITE`] and
/// infinity for a vertex with none: one pass over the cells' edges.
pub fn nearest_neighbours(d: &Delaunay) -> (Vec<u32>, Vec<f64>) {
    let (p, ranks) = (d.points(), d.ranks());
    // Squared distances decide, as a fan's nearest neighbour did.
    let mut best = vec![f64::INFINITY; p.len()];
    let mut near = vec![INFINITE; p.len()];
    let mut offer = |v: u32, u: u32, d2: f64| {
        let (v, w) = (v as usize, near[v as usize]);
        let closer = d2 < best[v]
            || (d2 == best[v] && w != INFINITE && ranks[u as usize] < ranks[w as usize]);
        if closer {
            best[v] = d2;
            near[v] = u;
        }
    };
    for cell in d.cell_slots() {
        if cell.is_free() {
            continue;
        }
        for j in 0..4 {
            for k in j + 1..4 {
                let (a, b) = (cell.v[j], cell.v[k]);
                if a == INFINITE || b == INFINITE {
                    continue;
                }
                let d2 = p[a as usize].distance_squared(p[b as usize]);
                offer(a, b, d2);
                offer(b, a, d2);
            }
        }
    }
    (near, best.into_iter().map(f64::sqrt).collect())
}

/// The region whose points were all triangulated: a tile's loaded box
/// (faces beyond all data at infinity), or all of space.
#[derive(Clone, Copy, Debug)]
pub struct Region {
    pub loaded: Aabb,
}

/// Relative slack on the proofs' spheres: their centres and radii are
/// computed in f64 and the proof must hold for the exact sphere.
const SLACK: f64 = 1e-7;

impl Region {
    #[cfg(test)]
    pub fn everything() -> Self {
        Region {
            loaded: Aabb::new(DVec3::splat(f64::NEG_INFINITY), DVec3::splat(f64::INFINITY)),
        }
    }

    pub fn is_everything(&self) -> bool {
        self.loaded.min.max_element() == f64::NEG_INFINITY
            && self.loaded.max.min_element() == f64::INFINITY
            && self.loaded.min.min_element() == f64::NEG_INFINITY
            && self.loaded.max.max_element() == f64::INFINITY
    }

    /// Whether the ball `(centre, radius)` lies inside the region.
    pub fn holds_ball(&self, centre: DVec3, radius: f64) -> bool {
        let r = radius * (1.0 + SLACK);
        (centre - r).cmpge(self.loaded.min).all() && (centre + r).cmple(self.loaded.max).all()
    }

    /// Whether every point within `radius` of `p` was loaded.
    pub fn holds_reach(&self, p: DVec3, radius: f64) -> bool {
        self.holds_ball(p, radius)
    }

    /// Whether the triangle `(i, w.a, w.b)` is proven Delaunay in the whole
    /// cloud (see the module doc).
    pub fn proves(&self, d: &Delaunay, i: u32, w: &Wing) -> bool {
        let p = d.points();
        let (o, a, b) = (p[i as usize], p[w.a as usize], p[w.b as usize]);
        let (u, v) = (a - o, b - o);
        let n = u.cross(v);
        let n2 = n.length_squared();
        if n2 == 0.0 {
            return false;
        }
        // Circumcentre of the triangle, relative to `o`.
        let cc = (v * u.length_squared() - u * v.length_squared()).cross(n) / (2.0 * n2);
        let unit = n / n2.sqrt();
        let r2 = cc.length_squared();
        // Sphere centred at cc + t unit: empty of apex q iff t is on the
        // side of t_q away from q's side of the plane.
        let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
        for &q in &w.apex {
            if q == INFINITE {
                continue;
            }
            let dq = p[q as usize] - o - cc;
            let h = dq.dot(unit);
            if h == 0.0 {
                return false;
            }
            let t = (dq.length_squared() - r2) / (2.0 * h);
            if h > 0.0 {
                hi = hi.min(t);
            } else {
                lo = lo.max(t);
            }
        }
        let r = r2.sqrt();
        let span = [lo, hi]
            .into_iter()
            .filter(|t| t.is_finite())
            .fold(0.0, |m: f64, t| m.max(t.abs()));
        let tol = SLACK * (r + span);
        if lo + tol > hi - tol {
            return false;
        }
        let t = 0.0f64.clamp(lo + tol, hi - tol);
        self.holds_ball(o + cc + unit * t, (r2 + t * t).sqrt())
    }
}
