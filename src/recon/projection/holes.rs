//! Small holes where fronts meet (a deviation from paper 2, which leaves
//! every hole a boundary): fronts meeting at a slant leave holes of a few
//! edges whose vertices see their neighbours along the front nearly in
//! line, so none of them can close its gap within the usual angle limit,
//! and the hole's far side may lie beyond a vertex's neighbour list. A gap
//! that opens onto such a hole is closed from its vertex with the hole's
//! vertices as candidates.

use super::cloud::{Cloud, Neighbourhoods};
use super::fan::{meets_nearby, HOLE_MAX_ANGLE_COS};
use super::frame::pseudo_angle;
use super::star::{Local, Star};
use super::surface::{State, Surface};

/// Longest hole (in edges) closed from one of its vertices whatever the
/// reach of its neighbour list.
pub const SMALL_HOLE: usize = 6;

/// The other boundary neighbour of `y` (not `prev`), when `y` has exactly
/// two boundary edges.
fn boundary_next(s: &Surface, y: u32, prev: u32) -> Option<u32> {
    match s.boundary_ends(y)? {
        [a, b] if a == prev => Some(b),
        [a, b] if b == prev => Some(a),
        _ => None,
    }
}

/// Closes the holes of three edges the growth left, each with one triangle
/// (a deviation from paper 2, which leaves every hole a boundary; the
/// growth itself closes such a hole from any of its vertices processed
/// after it formed, but where its last edge came from a vertex's fan the
/// others are not visited again). Seen on the 20:1 terrain at roof edges
/// and in its sparse ground, 2 to 4 local spacings across. The triangle
/// passes the checks every hole closure does: corner angles below
/// [`HOLE_MAX_ANGLE_COS`]'s, no triangle met in space, the directed-edge
/// rule. Holes in vertex order, each from its smallest vertex: the same in
/// every tile.
pub fn close_three_edge_holes<H: Neighbourhoods>(
    star: &mut Star,
    cloud: &Cloud<H>,
    s: &mut Surface,
) {
    for v in 0..s.state.len() as u32 {
        if !cloud.joinable[v as usize] {
            continue;
        }
        let Some([a, b]) = s.boundary_ends(v) else {
            continue;
        };
        let t = [v, a, b];
        let hole = v < a.min(b)
            && s.boundary_ends(a).is_some_and(|e| e.contains(&b))
            && t.iter().all(|&x| cloud.joinable[x as usize])
            && open_corners(cloud, t);
        if !hole {
            continue;
        }
        star.v = v;
        if meets_nearby(star, cloud, s, t) {
            continue;
        }
        let (tris, _) = s.edge_triangles(v, a);
        let (piece, _) = s.orientation(tris[0]);
        if s.try_add(t, piece).is_ok() || s.try_add([v, b, a], piece).is_ok() {
            for x in t {
                if s.is_closed(x) {
                    s.state[x as usize] = State::Completed;
                }
            }
        }
    }
}

/// Every corner angle of `t` below [`HOLE_MAX_ANGLE_COS`]'s, and `t` not
/// degenerate.
fn open_corners<H: Neighbourhoods>(cloud: &Cloud<H>, t: [u32; 3]) -> bool {
    let p = t.map(|x| cloud.points[x as usize]);
    (0..3).all(|i| {
        let (e1, e2) = (p[(i + 1) % 3] - p[i], p[(i + 2) % 3] - p[i]);
        let (l1, l2) = (e1.length(), e2.length());
        l1 > 0.0 && l2 > 0.0 && e1.dot(e2) >= HOLE_MAX_ANGLE_COS * l1 * l2
    })
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
                self.pts.push(Local {
                    id: x,
                    q,
                    ang,
                    height,
                });
                self.cands.push(self.pts.len() - 1);
            }
        }
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::recon::projection::cloud::Csr;
    use crate::recon::projection::probe::Probe;
    use glam::DVec3;

    /// A triangle `ABC` cut into the ring around an inner triangle
    /// `h0 h1 h2` (vertices 3, 4, 5), which is left out: a hole of three
    /// edges, every vertex of it with two boundary edges.
    fn ring() -> (Vec<DVec3>, Surface) {
        let points: Vec<DVec3> = [
            (-1.0, -0.6),
            (2.0, -0.6),
            (0.5, 2.0),
            (0.0, 0.0),
            (1.0, 0.0),
            (0.5, 0.8),
        ]
        .iter()
        .map(|&(x, y)| DVec3::new(x, y, 0.0))
        .collect();
        let mut s = Surface::new(points.len());
        for t in [
            [0, 1, 4],
            [0, 4, 3],
            [1, 2, 5],
            [1, 5, 4],
            [2, 0, 3],
            [2, 3, 5],
        ] {
            s.try_add(t, 0).unwrap();
        }
        (points, s)
    }

    fn close(points: &[DVec3], s: &mut Surface, joinable: &[bool]) {
        let n = points.len() as u32;
        let mut hoods = Csr::default();
        for i in 0..n {
            hoods.items.extend((0..n).filter(|&j| j != i));
            hoods.ends.push(hoods.items.len() as u32);
        }
        let ids: Vec<u64> = (0..u64::from(n)).collect();
        let (normals, spacing) = (vec![DVec3::Z; points.len()], vec![1.0; points.len()]);
        let centre = vec![true; points.len()];
        let probe = Probe::new(points, &ids, &spacing);
        let cloud = Cloud {
            points,
            normals: &normals,
            spacing: &spacing,
            hoods: &hoods,
            centre: &centre,
            joinable,
            probe: &probe,
            slack: 0.0,
        };
        close_three_edge_holes(&mut Star::default(), &cloud, s);
    }

    #[test]
    fn a_hole_of_three_edges_gets_its_triangle_wound_with_its_neighbours() {
        let (points, mut s) = ring();
        assert_eq!(s.boundary_ends(3), Some([4, 5]));
        close(&points, &mut s, &[true; 6]);
        assert_eq!(s.tris.len(), 7);
        let added = s.tris[6];
        // Wound as the ring is: counter-clockwise seen from +z.
        let p = added.map(|v| points[v as usize]);
        assert!((p[1] - p[0]).cross(p[2] - p[0]).z > 0.0, "{added:?}");
        for v in 3..6 {
            assert!(s.is_closed(v), "vertex {v}");
            assert_eq!(s.state[v as usize], State::Completed);
        }
        // Only the outer triangle's edges stay open.
        assert_eq!((0..6).map(|v| s.open_edges(v)).sum::<u32>(), 6);
    }

    #[test]
    fn a_hole_with_a_corner_the_job_may_not_join_stays_open() {
        let (points, mut s) = ring();
        let mut joinable = [true; 6];
        joinable[5] = false;
        close(&points, &mut s, &joinable);
        assert_eq!(s.tris.len(), 6);
        assert_eq!(s.open_edges(3), 2);
    }
}
