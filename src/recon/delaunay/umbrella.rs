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
/// is scratch. Wings come sorted by `(a, b)`.
pub fn umbrella(d: &Delaunay, i: u32, star: &mut Vec<u32>, out: &mut Vec<Wing>) {
    out.clear();
    d.star(i, star);
    for &c in star.iter() {
        let v = d.cell(c).v;
        let Some(s) = v.iter().position(|&x| x == i) else {
            continue;
        };
        let o = [v[(s + 1) & 3], v[(s + 2) & 3], v[(s + 3) & 3]];
        for k in 0..3 {
            let (a, b, w) = (o[k], o[(k + 1) % 3], o[(k + 2) % 3]);
            if a != INFINITE && b != INFINITE {
                out.push(Wing {
                    a: a.min(b),
                    b: a.max(b),
                    apex: [w, INFINITE],
                });
            }
        }
    }
    out.sort_unstable_by_key(|w| (w.a, w.b, w.apex[0]));
    // Each triangle came once from each of its two cells.
    let mut k = 0;
    for r in 0..out.len() {
        if k > 0 && out[k - 1].a == out[r].a && out[k - 1].b == out[r].b {
            out[k - 1].apex[1] = out[r].apex[0];
        } else {
            out[k] = out[r];
            k += 1;
        }
    }
    out.truncate(k);
}

/// Distance from every vertex to its nearest other vertex (a Delaunay
/// neighbour, always): one pass over the cells' edges.
pub fn nearest_distances(d: &Delaunay) -> Vec<f64> {
    let p = d.points();
    let mut nn = vec![f64::INFINITY; p.len()];
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
                let dist = p[a as usize].distance(p[b as usize]);
                let (a, b) = (a as usize, b as usize);
                nn[a] = nn[a].min(dist);
                nn[b] = nn[b].min(dist);
            }
        }
    }
    nn
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
