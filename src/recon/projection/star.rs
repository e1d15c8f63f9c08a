//! The local picture around one vertex `v` in its tangent plane (paper 2
//! sections 2.6-2.8): the oriented normal, the projected neighbours, the
//! visible region of `v` (the gaps between its triangles), the front edges
//! nearby, and the candidates that pass the three mutual-visibility rules.
//! `fan.rs` triangulates the gaps from it.

use super::cloud::{Cloud, Neighbourhoods};
use super::frame::{ccw_from, orient, pseudo_angle, segments_cross, Frame};
use super::surface::{State, Surface, Wedge, NONE};
use glam::{DVec2, DVec3};

/// A projected point of the neighbourhood.
#[derive(Clone, Copy, Debug)]
pub struct Local {
    pub id: u32,
    pub q: DVec2,
    pub ang: f64,
    /// Height over the tangent plane.
    pub height: f64,
}

/// An open counter-clockwise arc of directions (pseudo-angles), swept by a
/// triangle's corner, from the direction of `from` to that of `to`.
#[derive(Clone, Copy, Debug)]
pub struct Arc {
    pub start: f64,
    pub width: f64,
    pub from: u32,
    pub to: u32,
}

impl Arc {
    /// The corner of a triangle at `apex` towards `a` and `b` (in any order):
    /// the arc of the smaller angle, as a projected triangle covers.
    pub fn corner(apex: DVec2, a: (u32, DVec2), b: (u32, DVec2)) -> Self {
        let (a, b) = if orient(apex, a.1, b.1) >= 0.0 {
            (a, b)
        } else {
            (b, a)
        };
        let start = pseudo_angle(a.1 - apex);
        Arc {
            start,
            width: ccw_from(start, pseudo_angle(b.1 - apex)),
            from: a.0,
            to: b.0,
        }
    }

    /// Whether direction `ang` lies strictly inside.
    pub fn holds(&self, ang: f64) -> bool {
        let d = ccw_from(self.start, ang);
        d > 0.0 && d < self.width
    }
}

/// A part of the visible region of `v` (section 2.8): the directions from
/// its triangle edge towards `from` counter-clockwise to the one towards
/// `to`; `from`/`to` are `NONE` when `v` has no triangle (the whole circle).
#[derive(Clone, Copy, Debug)]
pub struct Gap {
    pub start: f64,
    pub width: f64,
    pub from: u32,
    pub to: u32,
}

impl Gap {
    /// Whether direction `ang` lies strictly inside.
    pub fn contains(&self, ang: f64) -> bool {
        if self.from == super::surface::NONE {
            return true;
        }
        let d = ccw_from(self.start, ang);
        d > 0.0 && d < self.width
    }
}

/// A boundary edge of the mesh near `v`, projected.
#[derive(Clone, Copy, Debug)]
pub struct FrontEdge {
    pub x: u32,
    pub y: u32,
    pub qx: DVec2,
    pub qy: DVec2,
}

/// The limits of a new triangle, from the parameters.
#[derive(Clone, Copy, Debug)]
pub struct Limits {
    pub max_edge: f64,
    pub tan_elevation: f64,
    pub cos_max_angle: f64,
}

/// Reused buffers: the hot loop allocates nothing once they have grown.
#[derive(Default)]
pub struct Star {
    pub v: u32,
    pub frame: Option<Frame>,
    /// The orientation piece new triangles join (its root).
    pub piece: u32,
    pub pts: Vec<Local>,
    pub gaps: Vec<Gap>,
    pub front: Vec<FrontEdge>,
    /// Indices into `pts` of the candidates, in angular order.
    pub cands: Vec<usize>,
    /// Distance from `v` to its farthest neighbour: circles up to this
    /// diameter through `v` hold only neighbours.
    pub reach: f64,
    wedges: Vec<Wedge>,
    arcs: Vec<Arc>,
    /// Arcs of other vertices in this frame: (vertex, first, end) into
    /// `corner_arcs`.
    arcs_of: Vec<(u32, u32, u32)>,
    corner_arcs: Vec<Arc>,
    /// The gap being triangulated closes a small hole.
    pub closing_hole: bool,
    /// Scratch of `fan::meets_nearby`: the vertices whose triangles it
    /// checks; for each point, `call << 32 | place` while it is among them
    /// (its place in `around`, at the call numbered `call`).
    pub around: Vec<u32>,
    pub marks: Vec<u64>,
    pub calls: u64,
    /// kNN answers (`fan.rs`).
    pub found: Vec<crate::spatial::Neighbour>,
}

impl Star {
    pub fn frame(&self) -> &Frame {
        // `build` sets the frame before anything reads it.
        self.frame.as_ref().unwrap_or(&FALLBACK_FRAME)
    }

    pub fn q(&self, cloud_points: &[DVec3], x: u32) -> DVec2 {
        self.frame().project(cloud_points[x as usize]).0
    }

    /// Builds the picture at `v`; false when `v` has no usable plane.
    pub fn build<H: Neighbourhoods>(
        &mut self,
        v: u32,
        cloud: &Cloud<H>,
        s: &mut Surface,
        lim: &Limits,
    ) -> bool {
        self.v = v;
        self.arcs_of.clear();
        self.corner_arcs.clear();
        let Some(n) = self.orient(v, cloud, s) else {
            return false;
        };
        self.frame = Some(Frame::new(cloud.points[v as usize], n));
        self.project_neighbours(v, cloud, s);
        self.find_gaps(cloud);
        self.find_front(cloud, s);
        self.select(cloud, s, lim);
        true
    }

    /// Section 2.6: the PCA normal, flipped to agree with the normal of the
    /// triangles already at `v` (those of its first triangle's piece, whose
    /// windings are comparable); the piece new triangles join.
    fn orient<H: Neighbourhoods>(
        &mut self,
        v: u32,
        cloud: &Cloud<H>,
        s: &mut Surface,
    ) -> Option<DVec3> {
        self.wedges.clear();
        self.wedges.extend(s.wedges(v));
        let pv = cloud.points[v as usize];
        let mut sum = DVec3::ZERO;
        self.piece = s.seed_piece(v);
        if let Some(first) = self.wedges.first() {
            let (root, _) = s.orientation(first.tri);
            self.piece = root;
            for w in &self.wedges {
                let (r, flip) = s.orientation(w.tri);
                if r == root {
                    let t =
                        (cloud.points[w.a as usize] - pv).cross(cloud.points[w.b as usize] - pv);
                    sum += if flip { -t } else { t };
                }
            }
        }
        let n = cloud.normals[v as usize];
        if n == DVec3::ZERO {
            return sum.try_normalize();
        }
        Some(if n.dot(sum) < 0.0 { -n } else { n })
    }

    fn project_neighbours<H: Neighbourhoods>(&mut self, v: u32, cloud: &Cloud<H>, s: &Surface) {
        self.pts.clear();
        self.reach = 0.0;
        let frame = *self.frame();
        for &u in cloud.hoods.get(v) {
            let d = cloud.points[u as usize] - frame.origin;
            self.reach = self.reach.max(d.length());
            if u == v || s.state[u as usize] == State::Unused {
                continue;
            }
            let (q, height) = frame.project(cloud.points[u as usize]);
            if q != DVec2::ZERO {
                self.pts.push(Local {
                    id: u,
                    q,
                    ang: pseudo_angle(q),
                    height,
                });
            }
        }
    }

    /// The visible region of `v`: the directions no triangle at `v` covers,
    /// as gaps from one triangle edge to the next (section 2.8).
    fn find_gaps<H: Neighbourhoods>(&mut self, cloud: &Cloud<H>) {
        self.gaps.clear();
        self.arcs.clear();
        if self.wedges.is_empty() {
            self.gaps.push(Gap {
                start: 0.0,
                width: 4.0,
                from: NONE,
                to: NONE,
            });
            return;
        }
        for i in 0..self.wedges.len() {
            let w = self.wedges[i];
            let (qa, qb) = (self.q(cloud.points, w.a), self.q(cloud.points, w.b));
            self.arcs
                .push(Arc::corner(DVec2::ZERO, (w.a, qa), (w.b, qb)));
        }
        for (i, arc) in self.arcs.iter().enumerate() {
            let end = arc.start + arc.width;
            let end = if end >= 4.0 { end - 4.0 } else { end };
            let covered = self
                .arcs
                .iter()
                .enumerate()
                .any(|(j, o)| j != i && (o.holds(end) || o.from == arc.to));
            if covered {
                continue;
            }
            // The gap runs to the nearest arc start counter-clockwise.
            let next = self
                .arcs
                .iter()
                .map(|o| (ccw_from(end, o.start), o.from))
                .filter(|&(d, _)| d > 0.0)
                .min_by(|a, b| a.0.total_cmp(&b.0));
            let (width, to) = next.unwrap_or((4.0, arc.from));
            self.gaps.push(Gap {
                start: end,
                width,
                from: arc.to,
                to,
            });
        }
    }

    /// Boundary edges (one triangle) at `v` and at its neighbours.
    fn find_front<H: Neighbourhoods>(&mut self, cloud: &Cloud<H>, s: &Surface) {
        self.front.clear();
        let frame = *self.frame();
        let open = |x: u32| matches!(s.state[x as usize], State::Fringe | State::Boundary);
        let xs = std::iter::once(self.v)
            .chain(self.pts.iter().map(|p| p.id).filter(|&x| open(x)))
            .filter(|&x| s.has_open_edges(x));
        let mut ends = [0u32; 32];
        for x in xs {
            let qx = frame.project(cloud.points[x as usize]).0;
            // Most front vertices have two boundary edges, which the
            // surface names without a walk.
            if let Some(two) = s.boundary_ends(x) {
                for y in two {
                    let qy = frame.project(cloud.points[y as usize]).0;
                    self.front.push(FrontEdge { x, y, qx, qy });
                }
                continue;
            }
            // A triangle edge at `x` is on the boundary when its far end
            // appears once among the ends of `x`'s triangles.
            let mut n = 0;
            for w in s.wedges(x) {
                if n + 2 > ends.len() {
                    break;
                }
                ends[n] = w.a;
                ends[n + 1] = w.b;
                n += 2;
            }
            let ends = &mut ends[..n];
            ends.sort_unstable();
            for i in 0..n {
                let y = ends[i];
                let single = (i == 0 || ends[i - 1] != y) && (i + 1 == n || ends[i + 1] != y);
                if single {
                    self.front.push(FrontEdge {
                        x,
                        y,
                        qx,
                        qy: frame.project(cloud.points[y as usize]).0,
                    });
                }
            }
        }
    }

    /// The arcs the triangles at `x` sweep around `x`, in `v`'s tangent
    /// plane. (Measured in `x`'s own plane instead, the 1M dragon kept more
    /// holes, 133 loops against 101; and one common plane is what rules out
    /// overlaps: triangles apart in some projection are apart in space.)
    pub fn arcs_at<H: Neighbourhoods>(
        &mut self,
        x: u32,
        cloud: &Cloud<H>,
        s: &Surface,
    ) -> (Frame, &[Arc]) {
        let frame = *self.frame();
        let found = self.arcs_of.iter().position(|e| e.0 == x);
        let k = match found {
            Some(k) => k,
            None => {
                let first = self.corner_arcs.len() as u32;
                let qx = frame.project(cloud.points[x as usize]).0;
                for w in s.wedges(x) {
                    let qa = frame.project(cloud.points[w.a as usize]).0;
                    let qb = frame.project(cloud.points[w.b as usize]).0;
                    self.corner_arcs.push(Arc::corner(qx, (w.a, qa), (w.b, qb)));
                }
                let end = self.corner_arcs.len() as u32;
                self.arcs_of.push((x, first, end));
                self.arcs_of.len() - 1
            }
        };
        let (_, first, end) = self.arcs_of[k];
        (frame, &self.corner_arcs[first as usize..end as usize])
    }

    /// Whether the open segment `x`-`y` crosses a front edge.
    pub fn crosses_front(&self, x: u32, qx: DVec2, y: u32, qy: DVec2) -> bool {
        self.front.iter().any(|e| {
            e.x != x && e.x != y && e.y != x && e.y != y && segments_cross(qx, qy, e.qx, e.qy)
        })
    }

    /// Candidates (section 2.8): neighbours in the visible region of `v`,
    /// with `v` in their own visible region, whose edge to `v` crosses no
    /// front edge, within the length and elevation limits.
    fn select<H: Neighbourhoods>(&mut self, cloud: &Cloud<H>, s: &Surface, lim: &Limits) {
        self.cands.clear();
        let pv = cloud.points[self.v as usize];
        let hv = cloud.spacing[self.v as usize];
        for i in 0..self.pts.len() {
            let p = self.pts[i];
            let u = p.id as usize;
            if matches!(s.state[u], State::Completed | State::Unused) || !cloud.joinable[u] {
                continue;
            }
            let d = cloud.points[u] - pv;
            if d.length() > lim.max_edge * hv.max(cloud.spacing[u]) {
                continue;
            }
            if p.height.abs() > lim.tan_elevation * p.q.length() {
                continue;
            }
            if !self.gaps.iter().any(|g| g.contains(p.ang)) {
                continue;
            }
            if self.wedges.iter().any(|w| w.a == p.id || w.b == p.id) {
                continue; // already connected: a gap bound joins by its own right
            }
            if self.crosses_front(self.v, DVec2::ZERO, p.id, p.q) {
                continue;
            }
            if s.has_triangles(p.id) {
                let towards_v = pseudo_angle(-p.q);
                let (_, arcs) = self.arcs_at(p.id, cloud, s);
                if arcs.iter().any(|a| a.holds(towards_v)) {
                    continue;
                }
            }
            self.cands.push(i);
        }
        let pts = &self.pts;
        self.cands.sort_by(|&a, &b| {
            pts[a]
                .ang
                .total_cmp(&pts[b].ang)
                .then(pts[a].id.cmp(&pts[b].id))
        });
    }
}

static FALLBACK_FRAME: Frame = Frame {
    origin: DVec3::ZERO,
    n: DVec3::Z,
    b1: DVec3::X,
    b2: DVec3::Y,
};
