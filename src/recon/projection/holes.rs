//! Small holes where fronts meet (a deviation from paper 2, which leaves
//! every hole a boundary): fronts meeting at a slant leave holes of a few
//! edges whose vertices see their neighbours along the front nearly in
//! line, so none of them can close its gap within the usual angle limit,
//! and the hole's far side may lie beyond a vertex's neighbour list. A gap
//! that opens onto such a hole is closed from its vertex with the hole's
//! vertices as candidates.

use super::cloud::{Cloud, Neighbourhoods};
use super::frame::pseudo_angle;
use super::star::{Local, Star};
use super::surface::{State, Surface, NONE};

/// Longest hole (in edges) closed from one of its vertices whatever the
/// reach of its neighbour list.
pub const SMALL_HOLE: usize = 6;

/// Largest corner angle of a triangle closing a small hole: 179 degrees.
pub const HOLE_MAX_ANGLE_COS: f64 = -0.99985;

/// The other boundary neighbour of `y` (not `prev`), when `y` has exactly
/// two boundary edges.
fn boundary_next(s: &Surface, y: u32, prev: u32) -> Option<u32> {
    if s.open_edges(y) != 2 {
        return None;
    }
    let mut ends = [0u32; 32];
    let mut n = 0;
    for w in s.wedges(y) {
        if n + 2 > ends.len() {
            return None;
        }
        ends[n] = w.a;
        ends[n + 1] = w.b;
        n += 2;
    }
    let ends = &mut ends[..n];
    ends.sort_unstable();
    let mut single = [NONE; 2];
    let mut k = 0;
    for i in 0..n {
        let y = ends[i];
        if (i == 0 || ends[i - 1] != y) && (i + 1 == n || ends[i + 1] != y) {
            if k == 2 {
                return None;
            }
            single[k] = y;
            k += 1;
        }
    }
    match (k, single) {
        (2, [a, b]) if a == prev => Some(b),
        (2, [a, b]) if b == prev => Some(a),
        _ => None,
    }
}

impl Star {
    /// Where the gap `g` opens onto a small hole (the mesh boundary leads
    /// from `from` round to `to` in at most [`SMALL_HOLE`] edges), the
    /// hole's vertices become candidates too, wherever they are: the hole is
    /// closed from `v` even when they lie beyond its list, and with corner
    /// angles up to [`HOLE_MAX_ANGLE_COS`]'s. Fronts meeting at a slant
    /// leave such holes, often of four edges, where every vertex sees its
    /// neighbours along the front nearly in line: a pair of slivers there
    /// is better than a hole (the 1M density step kept 22 of them).
    /// Returns whether the gap is such a hole.
    pub fn add_hole_candidates<H: Neighbourhoods>(
        &mut self,
        g: usize,
        cloud: &Cloud<H>,
        s: &Surface,
    ) -> bool {
        let gap = self.gaps[g];
        let mut path = [0u32; SMALL_HOLE];
        let (mut prev, mut at, mut len) = (self.v, gap.from, 0);
        while at != gap.to {
            if len == SMALL_HOLE {
                return false;
            }
            let Some(next) = boundary_next(s, at, prev) else {
                return false;
            };
            path[len] = at;
            len += 1;
            (prev, at) = (at, next);
        }
        let frame = *self.frame();
        for &x in &path[1..len] {
            let usable = matches!(s.state[x as usize], State::Fringe | State::Boundary)
                && cloud.joinable[x as usize];
            if !usable || self.cands.iter().any(|&c| self.pts[c].id == x) {
                continue;
            }
            let (q, height) = frame.project(cloud.points[x as usize]);
            let ang = pseudo_angle(q);
            if gap.contains(ang) {
                self.pts.push(Local { id: x, q, ang, height });
                self.cands.push(self.pts.len() - 1);
            }
        }
        true
    }
}
