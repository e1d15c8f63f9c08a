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
//! The smallest such sphere is tried first. When it pokes out, the store's
//! points beyond the region near it ([`Beyond`]) narrow the pencil as the
//! apexes did: a sphere left proves the triangle, and a pencil emptied
//! whole proves it absent from the cloud. Before the store was asked, a few
//! small triangles per tile whose only empty spheres were 80 to 115
//! spacings wide left fans unproven 80 spacings in, and the 10M dragon's
//! tiles doubted twice as deep as their margins.

use super::triangulation::{Delaunay, INFINITE};
use crate::geom::Aabb;
use crate::tiling::{Beyond, Seen};
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
#[derive(Clone, Copy)]
pub struct Region<'a> {
    pub loaded: Aabb,
    /// The points not loaded, when a ball poking out of `loaded` may be
    /// checked against them (a tiled run); `None`: nothing is known
    /// beyond `loaded`.
    pub beyond: Option<&'a Beyond<'a>>,
}

/// Relative slack on the proofs' spheres: their centres and radii are
/// computed in f64 and the proof must hold for the exact sphere.
const SLACK: f64 = 1e-7;

impl Region<'_> {
    #[cfg(test)]
    pub fn everything() -> Self {
        Region {
            loaded: Aabb::new(DVec3::splat(f64::NEG_INFINITY), DVec3::splat(f64::INFINITY)),
            beyond: None,
        }
    }

    pub fn is_everything(&self) -> bool {
        self.loaded.min.max_element() == f64::NEG_INFINITY
            && self.loaded.max.min_element() == f64::INFINITY
            && self.loaded.min.min_element() == f64::NEG_INFINITY
            && self.loaded.max.max_element() == f64::INFINITY
    }

    /// Whether every point of the cloud in the ball `(centre, radius)` was
    /// loaded: the ball lies inside the loaded region, or the store shows
    /// no other point in it.
    pub fn holds_ball(&self, centre: DVec3, radius: f64) -> bool {
        let r = radius * (1.0 + SLACK);
        let inside =
            (centre - r).cmpge(self.loaded.min).all() && (centre + r).cmple(self.loaded.max).all();
        inside || self.beyond.is_some_and(|b| b.ball_is_empty(centre, r))
    }

    /// Whether every point within `radius` of `p` was loaded.
    pub fn holds_reach(&self, p: DVec3, radius: f64) -> bool {
        self.holds_ball(p, radius)
    }

    /// For a point whose nearest loaded neighbour lies `nn` away and whose
    /// ball of that radius pokes out of the region (the caller checked it
    /// is not held): its nearest distance in the whole cloud, and when
    /// that neighbour is not loaded, an upper bound on the neighbour's own
    /// nearest distance (the nearest other point seen). `None` when nothing
    /// is known beyond.
    pub fn nearest_beyond(&self, p: DVec3, nn: f64) -> Option<(f64, Option<f64>)> {
        if !nn.is_finite() {
            return None;
        }
        let mut seen = Vec::new();
        let beyond = self.beyond?;
        if beyond.each_outside(p, nn, |q| {
            seen.push(q);
            true
        }) != Seen::All
        {
            return None;
        }
        let Some(&y) = seen
            .iter()
            .min_by(|a, b| a.distance(p).total_cmp(&b.distance(p)))
        else {
            return Some((nn, None));
        };
        let d = y.distance(p);
        if d >= nn {
            return Some((nn, None));
        }
        let others = seen.iter().filter(|&&q| q != y).map(|q| q.distance(y));
        Some((d, Some(others.fold(d, f64::min))))
    }

    /// Whether the triangle `(i, w.a, w.b)` is the whole cloud's (see the
    /// module doc).
    pub fn triangle(&self, d: &Delaunay, i: u32, w: &Wing) -> Proof {
        let p = d.points();
        let Some(mut pencil) = Pencil::new(p[i as usize], p[w.a as usize], p[w.b as usize]) else {
            return Proof::Unknown;
        };
        for &q in &w.apex {
            if q != INFINITE && !pencil.exclude(p[q as usize]) {
                return Proof::Unknown;
            }
        }
        let Some(t) = pencil.smallest() else {
            return Proof::Unknown;
        };
        let (centre, radius) = pencil.sphere(t);
        if self.holds_ball(centre, radius) {
            return Proof::Held;
        }
        // The smallest sphere holds a point not loaded, or nothing is known
        // beyond: narrow the pencil by the unloaded points near it, exactly
        // as by the apexes. The triangle is the cloud's when a sphere is
        // left, and not the cloud's when none is left of the whole pencil.
        let Some(beyond) = self.beyond else {
            return Proof::Unknown;
        };
        let (lo, hi) = (pencil.lo, pencil.hi);
        let Some((centre, radius)) = pencil.narrow_near(t) else {
            return Proof::Unknown;
        };
        let whole = (pencil.lo, pencil.hi) == (lo, hi);
        match beyond.each_outside(centre, radius * (1.0 + SLACK), |q| pencil.exclude(q)) {
            Seen::All if pencil.smallest().is_some() => Proof::Held,
            Seen::Stopped if whole && pencil.sure && pencil.clearly_empty() => Proof::Absent,
            _ => Proof::Unknown,
        }
    }
}

/// What a tile knows of one of its Delaunay triangles in the whole cloud.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Proof {
    /// An empty sphere of it holds no point of the cloud: it is the cloud's.
    Held,
    /// Every sphere through it holds a point of the cloud: it is not.
    Absent,
    Unknown,
}

/// The spheres through a triangle's corners `o, a, b`: centred at
/// `o + cc + t * unit`, for `t` in `(lo, hi)`, the part not yet shown to
/// hold a point.
struct Pencil {
    o: DVec3,
    cc: DVec3,
    unit: DVec3,
    r2: f64,
    lo: f64,
    hi: f64,
    /// No point met lay in the triangle's plane (which `exclude` cannot
    /// place, so a pencil it emptied says nothing).
    sure: bool,
}

impl Pencil {
    /// Every sphere through the corners (`None`: a degenerate triangle).
    fn new(o: DVec3, a: DVec3, b: DVec3) -> Option<Self> {
        let (u, v) = (a - o, b - o);
        let n = u.cross(v);
        let n2 = n.length_squared();
        if n2 == 0.0 {
            return None;
        }
        // Circumcentre of the triangle, relative to `o`.
        let cc = (v * u.length_squared() - u * v.length_squared()).cross(n) / (2.0 * n2);
        Some(Pencil {
            o,
            cc,
            unit: n / n2.sqrt(),
            r2: cc.length_squared(),
            lo: f64::NEG_INFINITY,
            hi: f64::INFINITY,
            sure: true,
        })
    }

    /// Keeps the spheres that do not hold `q`: those with `t` on the side
    /// of `t_q` away from `q`'s side of the plane. False when none is left
    /// (a point in the plane ends the proof: it is rare, and the sphere
    /// test there would be a circle test).
    fn exclude(&mut self, q: DVec3) -> bool {
        let dq = q - self.o - self.cc;
        let h = dq.dot(self.unit);
        if h == 0.0 {
            self.sure = false;
            return false;
        }
        let t = (dq.length_squared() - self.r2) / (2.0 * h);
        if h > 0.0 {
            self.hi = self.hi.min(t);
        } else {
            self.lo = self.lo.max(t);
        }
        self.lo < self.hi
    }

    /// The `t` of the smallest sphere left, kept a relative slack inside
    /// the interval (the spheres are computed in f64 and the proof must
    /// hold for the exact ones); `None` when the slack closes it.
    fn smallest(&self) -> Option<f64> {
        let tol = self.tolerance();
        (self.lo + tol <= self.hi - tol).then(|| 0.0f64.clamp(self.lo + tol, self.hi - tol))
    }

    /// Whether no sphere is left by more than the slack either way, so the
    /// exact spheres hold a point too.
    fn clearly_empty(&self) -> bool {
        let tol = self.tolerance();
        self.lo - tol > self.hi + tol
    }

    fn tolerance(&self) -> f64 {
        let span = [self.lo, self.hi]
            .into_iter()
            .filter(|t| t.is_finite())
            .fold(0.0, |m: f64, t| m.max(t.abs()));
        SLACK * (self.r2.sqrt() + span)
    }

    fn sphere(&self, t: f64) -> (DVec3, f64) {
        (self.o + self.cc + self.unit * t, (self.r2 + t * t).sqrt())
    }

    /// Keeps the spheres within one radius of the sphere at `t` along the
    /// pencil (farther ones are larger and would read more points for no
    /// better proof), and returns a ball holding all of them.
    fn narrow_near(&mut self, t: f64) -> Option<(DVec3, f64)> {
        let reach = self.sphere(t).1;
        self.lo = self.lo.max(t - reach);
        self.hi = self.hi.min(t + reach);
        if self.lo >= self.hi {
            return None;
        }
        // rad(t) is convex in t, so the end spheres are the largest.
        let (a, b) = (self.sphere(self.lo), self.sphere(self.hi));
        let mid = self.sphere((self.lo + self.hi) / 2.0).0;
        Some((mid, (self.hi - self.lo) / 2.0 + a.1.max(b.1)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The unit right triangle in z = 0: circumcentre (0.5, 0.5, 0), and
    /// the pencil's spheres centred on the vertical through it.
    fn right_triangle() -> Pencil {
        Pencil::new(DVec3::ZERO, DVec3::X, DVec3::Y).unwrap()
    }

    #[test]
    fn a_point_on_each_side_empties_the_pencil() {
        let mut pencil = right_triangle();
        assert_eq!(pencil.smallest(), Some(0.0));
        // Just above the circumcentre: only spheres centred far below
        // (t <= -2.45) keep it out.
        assert!(pencil.exclude(DVec3::new(0.5, 0.5, 0.1)));
        let t = pencil.smallest().unwrap();
        assert!((t + 2.45).abs() < 1e-6, "{t}");
        let (centre, radius) = pencil.sphere(t);
        assert!(centre.distance(DVec3::new(0.5, 0.5, 0.1)) >= radius - 1e-9);
        // A point below as well leaves no sphere: the triangle is not
        // Delaunay, and the pencil knows it for sure.
        assert!(!pencil.exclude(DVec3::new(0.5, 0.5, -0.1)));
        assert!(pencil.smallest().is_none());
        assert!(pencil.sure && pencil.clearly_empty());
    }

    #[test]
    fn a_point_in_the_plane_proves_nothing() {
        let mut pencil = right_triangle();
        assert!(!pencil.exclude(DVec3::new(0.4, 0.4, 0.0)));
        assert!(!pencil.sure);
    }

    #[test]
    fn far_points_leave_the_pencil_whole() {
        let mut pencil = right_triangle();
        assert!(pencil.exclude(DVec3::new(0.5, 0.5, 5.0)));
        assert!(pencil.exclude(DVec3::new(0.5, 0.5, -5.0)));
        assert_eq!(pencil.smallest(), Some(0.0));
        let (lo, hi) = (pencil.lo, pencil.hi);
        assert!(lo < -2.0 && hi > 2.0, "{lo} {hi}");
        // The ball round the spheres within one radius of the smallest
        // holds them all.
        let (centre, radius) = pencil.narrow_near(0.0).unwrap();
        for t in [pencil.lo, 0.0, pencil.hi] {
            let (c, r) = pencil.sphere(t);
            assert!(c.distance(centre) + r <= radius + 1e-12);
        }
    }
}
