//! Triangulating the visible region of a vertex (paper 2 section 2.9).
//!
//! Deviation in how, not in what: the paper joins `v` to its candidates in
//! angular order and then flips the fan's edges until it is Delaunay in the
//! tangent plane (fig. 3). Here the Delaunay fan is walked directly: from
//! the edge bounding a gap, the next neighbour is the candidate whose
//! circle through `v` and the current neighbour is emptiest (the smallest
//! bulge into the gap), as in gift-wrapping Delaunay construction. The
//! angular fan of the paper, before its flips, joins `v` to far candidates
//! whose chain edges are long and thin; checking those before flipping
//! refused most of them (on a 20k-point sphere, 5,800 refusals for edge
//! length out of 7,000), and flipping first needs every ear checked
//! anyway. The walk yields the triangles the flips aim at, one at a time,
//! each checked once.
//!
//! A gap is walked from its first edge counter-clockwise, and where that
//! stops short of the gap's far edge, from the far edge clockwise; a
//! vertex with no triangle yet starts from its nearest candidate.
//!
//! Every triangle is checked before it is added: edge lengths within the
//! local limit, corner angles below the largest allowed, no corner
//! overlapping the triangles already at that vertex (the visible-region
//! rule at every corner, which keeps the surface from folding over
//! itself), no new edge crossing a front edge, no vertex of the mesh inside
//! it, no triangle round its corners met in space, and finally the
//! surface's directed-edge rule.
//!
//! The test in space runs for every triangle, not only where the plane
//! looks unreliable (a curved neighbourhood or a long edge, as before):
//! depth-camera frames fold flat triangles onto their neighbours where
//! nothing looked curved (`tests/projection_real.rs`), and the test keeps
//! the coordinates' rounding as clearance (`mesh::clearance`), since the
//! kernel's f32 coordinates are not the ones written.

use super::cloud::{Cloud, Neighbourhoods};
use super::frame::{arcs_overlap, orient, strictly_inside};
use super::star::{Arc, Limits, Star};
use super::surface::{State, Surface, NONE};
use crate::mesh::clearance::meet_within;
use glam::DVec2;

/// Largest corner angle of a triangle closing a small hole (`holes`): 179
/// degrees.
pub const HOLE_MAX_ANGLE_COS: f64 = -0.99985;

/// A walk's current edge end.
#[derive(Clone, Copy, Debug)]
struct End {
    id: u32,
    q: DVec2,
}

/// Reused buffers.
#[derive(Default)]
pub struct Fan {
    /// Triangles added at the last call.
    pub added: Vec<[u32; 3]>,
    used: Vec<u32>,
}

impl Fan {
    /// Triangulates every gap of `star`; the triangles added are left in
    /// `added`.
    pub fn triangulate<H: Neighbourhoods>(
        &mut self,
        star: &mut Star,
        cloud: &Cloud<H>,
        s: &mut Surface,
        lim: &Limits,
    ) {
        self.added.clear();
        for g in 0..star.gaps.len() {
            let gap = star.gaps[g];
            if gap.from == NONE {
                star.closing_hole = false;
                self.whole_circle(star, cloud, s, lim);
            } else {
                star.closing_hole = star.add_hole_candidates(g, cloud, s);
                let from = End {
                    id: gap.from,
                    q: star.q(cloud.points, gap.from),
                };
                let to = End {
                    id: gap.to,
                    q: star.q(cloud.points, gap.to),
                };
                let reached = self.walk(star, cloud, s, lim, from, Some(to), g, true);
                if reached.id != to.id {
                    self.walk(star, cloud, s, lim, to, Some(reached), g, false);
                }
            }
        }
    }

    /// A vertex without triangles: from its nearest candidate round both
    /// ways.
    fn whole_circle<H: Neighbourhoods>(
        &mut self,
        star: &mut Star,
        cloud: &Cloud<H>,
        s: &mut Surface,
        lim: &Limits,
    ) {
        let Some(&first) = star.cands.iter().min_by(|&&a, &&b| {
            let (pa, pb) = (star.pts[a], star.pts[b]);
            pa.q.length_squared()
                .total_cmp(&pb.q.length_squared())
                .then(pa.id.cmp(&pb.id))
        }) else {
            return;
        };
        let p = star.pts[first];
        let start = End { id: p.id, q: p.q };
        let reached = self.walk(star, cloud, s, lim, start, Some(start), 0, true);
        if reached.id != start.id || self.added.is_empty() {
            self.walk(star, cloud, s, lim, start, Some(reached), 0, false);
        }
    }

    /// Walks gap `g` from `start` (counter-clockwise when `ccw`) adding
    /// Delaunay triangles until it reaches `stop` or finds no acceptable
    /// next neighbour; returns where it stopped.
    #[allow(clippy::too_many_arguments)]
    fn walk<H: Neighbourhoods>(
        &mut self,
        star: &mut Star,
        cloud: &Cloud<H>,
        s: &mut Surface,
        lim: &Limits,
        start: End,
        stop: Option<End>,
        g: usize,
        ccw: bool,
    ) -> End {
        let mut cur = start;
        self.used.clear();
        for _ in 0..=star.cands.len() {
            let Some(next) = next_neighbour(star, g, cur, stop, ccw, &self.used) else {
                break;
            };
            let t = if ccw {
                [(star.v, DVec2::ZERO), (cur.id, cur.q), (next.id, next.q)]
            } else {
                [(star.v, DVec2::ZERO), (next.id, next.q), (cur.id, cur.q)]
            };
            if !t.iter().all(|x| cloud.joinable[x.0 as usize]) {
                break;
            }
            let edges = s.edges(t.map(|x| x.0));
            if !acceptable(star, cloud, s, lim, t, edges.map(|e| e.1 > 0))
                || !self.add(s, t.map(|x| x.0), star.piece, edges)
            {
                break;
            }
            self.used.push(next.id);
            cur = next;
            if stop.is_some_and(|e| e.id == next.id) {
                break;
            }
        }
        cur
    }

    fn add(
        &mut self,
        s: &mut Surface,
        t: [u32; 3],
        piece: u32,
        edges: [([u32; 2], usize); 3],
    ) -> bool {
        match s.try_add_on(t, piece, edges) {
            Ok(_) => {
                self.added.push(t);
                true
            }
            Err(_) => false,
        }
    }
}

/// The Delaunay neighbour after `cur` on the walk's side: among the gap's
/// candidates (and `stop`) strictly on that side of `v -> cur` and not yet
/// used, the one whose circle through `v`, `cur` and itself reaches least
/// into that side (the empty circle).
fn next_neighbour(
    star: &Star,
    g: usize,
    cur: End,
    stop: Option<End>,
    ccw: bool,
    used: &[u32],
) -> Option<End> {
    let gap = star.gaps[g];
    let side = |q: DVec2| {
        let o = orient(DVec2::ZERO, cur.q, q);
        if ccw {
            o
        } else {
            -o
        }
    };
    let bulge = |q: DVec2| (q.length_squared() - cur.q.dot(q)) / side(q);
    let mut best: Option<(f64, End)> = None;
    let mut consider = |e: End| {
        if e.id == cur.id || side(e.q) <= 0.0 {
            return;
        }
        let b = bulge(e.q);
        if best.is_none_or(|(bb, be)| b < bb || (b == bb && e.id < be.id)) {
            best = Some((b, e));
        }
    };
    for &c in &star.cands {
        let p = star.pts[c];
        if gap.contains(p.ang) && !used.contains(&p.id) {
            consider(End { id: p.id, q: p.q });
        }
    }
    if let Some(e) = stop {
        consider(e);
    }
    best.map(|(_, e)| e)
}

/// Whether the counter-clockwise (in the star's frame) triangle `t`, whose
/// edge `t[i]`-`t[i + 1]` is in the mesh when `existing[i]`, may be added;
/// see the module docs for the list of checks.
fn acceptable<H: Neighbourhoods>(
    star: &mut Star,
    cloud: &Cloud<H>,
    s: &Surface,
    lim: &Limits,
    t: [(u32, DVec2); 3],
    existing: [bool; 3],
) -> bool {
    // A triangle whose three edges exist closes a three-edge hole: it adds
    // no edge, and a sliver there is better than a hole. Closing a hole
    // (this one, or a small one `v`'s gap opens onto), the corners are not
    // held to the tangent plane's picture, which folds near creases; the
    // exact test in space keeps the surface from crossing itself instead.
    let closes_hole = existing.iter().all(|&e| e);
    let hole = closes_hole || star.closing_hole;
    let ids = t.map(|x| x.0);
    (closes_hole || shape_ok(cloud, lim, ids, star.closing_hole))
        && (hole || corners_free(star, cloud, s, t))
        && (0..3).all(|i| {
            let (a, b) = (t[i], t[(i + 1) % 3]);
            existing[i] || !star.crosses_front(a.0, a.1, b.0, b.1)
        })
        && !holds_a_vertex(star, s, t)
        && (closes_hole || !big_and_not_empty(star, cloud, s, ids))
        && !meets_nearby(star, cloud, s, ids)
}

/// For a triangle too big for `v`'s neighbour list to vouch for (a corner
/// beyond the list's reach): whether a point (other than its corners, and
/// not left out) inside its smallest enclosing ball lies over it, as seen
/// along its normal (`probe.rs` finds the ball's points). A long triangle
/// across a gap otherwise lays itself over triangles of points `v` does
/// not see.
fn big_and_not_empty<H: Neighbourhoods>(
    star: &mut Star,
    cloud: &Cloud<H>,
    s: &Surface,
    t: [u32; 3],
) -> bool {
    let p = t.map(|x| cloud.points[x as usize]);
    // With every corner within the list's reach of `v`, so is the whole
    // triangle: the list holds every point inside, `holds_a_vertex` has
    // seen them.
    let pv = cloud.points[star.v as usize];
    if p.iter().all(|c| (*c - pv).length() <= star.reach) {
        return false;
    }
    let (centre, r2) = enclosing_ball(p);
    let n = (p[1] - p[0]).cross(p[2] - p[0]);
    if n == glam::DVec3::ZERO {
        return true;
    }
    let mut found = std::mem::take(&mut star.found);
    cloud.probe.within(centre, r2.sqrt(), &mut found);
    let hit = found.iter().any(|q| {
        q.dist2 < r2
            && !t.contains(&q.index)
            && s.state[q.index as usize] != State::Unused
            && above_triangle(p, n, cloud.points[q.index as usize])
    });
    star.found = found;
    hit
}

/// Smallest ball holding triangle `p`: the circumscribed one when acute,
/// else the one on its longest edge. Centre and squared radius.
fn enclosing_ball(p: [glam::DVec3; 3]) -> (glam::DVec3, f64) {
    for i in 0..3 {
        let (a, b, c) = (p[i], p[(i + 1) % 3], p[(i + 2) % 3]);
        if (b - a).dot(c - a) <= 0.0 {
            let m = 0.5 * (b + c);
            return (m, (b - m).length_squared());
        }
    }
    let (a, ab, ac) = (p[0], p[1] - p[0], p[2] - p[0]);
    let n = ab.cross(ac);
    let centre = a
        + (ac.length_squared() * n.cross(ab) + ab.length_squared() * ac.cross(n))
            / (2.0 * n.length_squared());
    (centre, (centre - a).length_squared())
}

/// Whether `q` projects strictly inside triangle `p` along its normal `n`.
fn above_triangle(p: [glam::DVec3; 3], n: glam::DVec3, q: glam::DVec3) -> bool {
    (0..3).all(|i| (p[(i + 1) % 3] - p[i]).cross(q - p[i]).dot(n) > 0.0)
}

/// Edges within the local limit, corner angles below the largest allowed.
fn shape_ok<H: Neighbourhoods>(cloud: &Cloud<H>, lim: &Limits, t: [u32; 3], in_hole: bool) -> bool {
    let p = t.map(|x| cloud.points[x as usize]);
    let cos_max = if in_hole {
        HOLE_MAX_ANGLE_COS
    } else {
        lim.cos_max_angle
    };
    let h = t.map(|x| cloud.spacing[x as usize]);
    (0..3).all(|i| {
        let (j, k) = ((i + 1) % 3, (i + 2) % 3);
        let (e1, e2) = (p[j] - p[i], p[k] - p[i]);
        e1.length() <= lim.max_edge * h[i].max(h[j])
            && e1.dot(e2) >= cos_max * e1.length() * e2.length()
    })
}

/// No corner of `t` overlaps the triangles already at that vertex (section
/// 2.8 rule (b), at every corner; `v`'s own corner lies in its gap).
fn corners_free<H: Neighbourhoods>(
    star: &mut Star,
    cloud: &Cloud<H>,
    s: &Surface,
    t: [(u32, DVec2); 3],
) -> bool {
    (0..3).all(|i| {
        let x = t[i].0;
        if x == star.v || !s.has_triangles(x) {
            return true;
        }
        let corner = Arc::corner(t[i].1, t[(i + 1) % 3], t[(i + 2) % 3]);
        let (_, arcs) = star.arcs_at(x, cloud, s);
        !arcs
            .iter()
            .any(|a| arcs_overlap(a.start, a.width, corner.start, corner.width))
    })
}

/// A vertex of the mesh (not free, not unused) strictly inside `t`.
fn holds_a_vertex(star: &Star, s: &Surface, t: [(u32, DVec2); 3]) -> bool {
    star.pts.iter().any(|l| {
        strictly_inside(l.q, t[0].1, t[1].1, t[2].1)
            && t.iter().all(|c| c.0 != l.id)
            && !matches!(s.state[l.id as usize], State::Free | State::Unused)
    })
}

/// Whether triangle `t` meets, in space, a triangle at `v` or at one of its
/// neighbours (exact test, shared vertices handled: `mesh::intersect`).
///
/// The three lists overlap, and each triangle sits at three vertices: the
/// vertices are deduplicated first (at most `1 + 3k`), each marked with its
/// place, and a triangle is tested only at the first of its corners among
/// them, only when its box meets `t`'s, so the exact test runs once each
/// (a list of every triangle seen, scanned per triangle, was a sixth of the
/// whole run on the 1M dragon).
pub(super) fn meets_nearby<H: Neighbourhoods>(
    star: &mut Star,
    cloud: &Cloud<H>,
    s: &Surface,
    t: [u32; 3],
) -> bool {
    let p = t.map(|x| cloud.points[x as usize]);
    let (lo, hi) = (p[0].min(p[1]).min(p[2]), p[0].max(p[1]).max(p[2]));
    if star.marks.len() < cloud.points.len() {
        star.marks.resize(cloud.points.len(), 0);
    }
    star.calls += 1;
    let call = star.calls;
    let marks = &mut star.marks;
    let around = &mut star.around;
    around.clear();
    let mut add = |y: u32| {
        let m = &mut marks[y as usize];
        if *m >> 32 != call {
            *m = call << 32 | around.len() as u64;
            around.push(y);
        }
    };
    add(star.v);
    for x in t {
        add(x);
        cloud.hoods.get(x).iter().for_each(|&y| add(y));
    }
    let earlier = |y: u32, place: usize| {
        let m = marks[y as usize];
        m >> 32 == call && ((m & 0xffff_ffff) as usize) < place
    };
    for (place, &x) in around.iter().enumerate() {
        for w in s.wedges(x) {
            if earlier(w.a, place) || earlier(w.b, place) {
                continue;
            }
            let o = s.tris[w.tri as usize];
            let q = o.map(|y| cloud.points[y as usize]);
            let (olo, ohi) = (q[0].min(q[1]).min(q[2]), q[0].max(q[1]).max(q[2]));
            if olo.cmpgt(hi).any() || lo.cmpgt(ohi).any() {
                continue;
            }
            if meet_within(t, &p, o, &q, cloud.slack) {
                return true;
            }
        }
    }
    false
}
