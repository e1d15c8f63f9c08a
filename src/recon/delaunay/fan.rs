//! Paper 4 section 2.2, algorithm 1 ("incremental learning"): the fan of
//! nearly flat small triangles around each sample, read off the 3-D
//! Delaunay triangulation.
//!
//! For sample `i`: (1) `x`, its nearest Delaunay neighbour (nearest-edge
//! rule); (2) among the Delaunay triangles on edge `ix`, `ixy` with the
//! largest angle opposite `ix` (largest-angle rule); (3) among the triangles
//! on `iy` at an obtuse dihedral angle to `ixy` (obtuse-dihedral rule), `iyz`
//! with the largest angle opposite `iy`; if its circumradius is below the
//! hole radius it is selected and the walk turns on, otherwise a boundary
//! was met (boundary rule) and the walk goes the other way from `ixy`;
//! (4) until a selected triangle comes round again (`i` is interior) or a
//! second boundary is met (`i` is a boundary point). Inheritance first: on
//! an edge that already has selected triangles, choose only among them.
//!
//! Deviations, for results that do not depend on the order samples are
//! visited (so tiles and threads agree exactly):
//! - Inheritance reads the fans of a first round without it (every sample's
//!   fan by the plain rules), not the fans of the samples visited before.
//! - Paper 4 does not say whether `ixy` itself must be small; a sample
//!   whose best triangle at its nearest edge spans a hole selects nothing.
//! - The hole radius is per triangle (see [`Hole`]) unless given.
//!
//! Ties (equal angles) go to the smaller input id. A fan is *proven* when
//! each of its choices is the one the whole cloud's triangulation would
//! give ([`Region::proves`]); a tile whose core needs an unproven fan asks
//! for a wider margin.

use super::cleanup::across;
use super::triangulation::{Delaunay, INFINITE};
use super::umbrella::{umbrella, Proof, Region, Wing};
use glam::DVec3;

/// The sampling-hole radius delta of paper 4 (definition 4): triangles with
/// a larger circumradius are holes in the sampling, i.e. boundaries.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Hole {
    /// One radius everywhere (paper 4 gives it relative to the bounding
    /// sphere; here it is absolute, in the input's units).
    Absolute(f64),
    /// Deviation: `multiple` times the largest spacing of the triangle's
    /// corners, so the threshold follows the local sampling density. A
    /// corner's spacing is its nearest-neighbour distance, but at most
    /// [`OUTLIER`] times its nearest neighbour's own, and at most
    /// `ceiling` ([`SPARSEST`] times the cloud's median spacing; infinite
    /// for none).
    Local { multiple: f64, ceiling: f64 },
}

/// Default multiple for [`Hole::Local`].
pub const LOCAL_HOLE: f64 = 5.0;

/// Deviation: a sample farther from its nearest neighbour than this many
/// times that neighbour's own nearest-neighbour distance is an outlier
/// beside denser samples, not sparse sampling, and its spacing is capped
/// there. Uncapped, a stray sample 37 spacings from the 10M noisy dragon
/// made triangles of 185 spacings selectable, and a tile near it doubted
/// 200 spacings deep (a margin no 512 MiB plan holds). Capped at 4, it
/// would have changed the selectability of 148 of the 1M dragon's 2M
/// triangles (at 3: 362; at 8: 17); a density step keeps its bridging
/// triangles, as their corners' spacings differ by the step's square root.
pub const OUTLIER: f64 = 4.0;

/// Deviation: no corner's spacing counts for more than this many times the
/// cloud's median spacing (`super::scale`), so no triangle wider than
/// [`LOCAL_HOLE`] times that is selected. Paper 4's hole radius is global;
/// ours follows the local spacing up to this ceiling. A few samples on the
/// 10M noisy dragon's filaments lie 30 to 38 spacings from any other, beside
/// neighbours as sparse (the [`OUTLIER`] cap does not reach them), and their
/// triangles, over a hundred spacings wide, made tiles doubt deeper than any
/// margin a 512 MiB plan holds. Points above 8 times the median spacing: 2
/// of the 1M dragon's, 6 of the 10M's; a scan sparser than that somewhere
/// (a density ratio above 64:1) gets boundaries there, or `--hole`.
pub const SPARSEST: f64 = 8.0;

/// Whether a triangle is in the first round's fans (for inheritance).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Membership {
    In,
    Out,
    /// Only a fan that could not be proven could tell.
    Unknown,
}

/// One sample's fan.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Fan {
    /// Selected triangles, corners sorted.
    pub tris: Vec<[u32; 3]>,
    /// The fan closed (paper 4: an interior point).
    pub interior: bool,
    pub proven: bool,
}

/// Reusable buffers of one worker.
#[derive(Default)]
pub struct FanScratch {
    star: Vec<u32>,
    wings: Vec<Wing>,
    /// A fan step's candidates: cosine, apex, wing, first-round membership.
    ranked: Vec<(f64, u32, Wing, Membership)>,
}

pub struct Selector<'a> {
    pub d: &'a Delaunay,
    /// Nearest-neighbour distance per vertex, and whether it is proven.
    pub nn: &'a [f64],
    /// Each vertex's nearest neighbour ([`INFINITE`]: none).
    pub near: &'a [u32],
    pub nn_proven: &'a [bool],
    /// Per vertex: an upper bound on its spacing in the whole cloud (see
    /// [`Selector::spacing`]), read where the spacing is not proven.
    pub spacing_bound: &'a [f64],
    pub hole: Hole,
    pub region: Region<'a>,
}

/// Corners sorted: the triangle's identity.
pub fn tri(a: u32, b: u32, c: u32) -> [u32; 3] {
    let mut t = [a, b, c];
    t.sort_unstable();
    t
}

impl Selector<'_> {
    fn p(&self, v: u32) -> DVec3 {
        self.d.points()[v as usize]
    }

    /// The fan of `i`; `inherited` says which triangles the first round
    /// selected (`None`: the first round itself).
    pub fn fan(
        &self,
        i: u32,
        inherited: Option<&dyn Fn([u32; 3]) -> Membership>,
        s: &mut FanScratch,
    ) -> Fan {
        umbrella(self.d, i, &mut s.star, &mut s.wings);
        let mut fan = Fan {
            proven: true,
            ..Fan::default()
        };
        let Some(x) = self.nearest(i, &mut fan.proven) else {
            return fan;
        };
        let mut walk = Walk {
            sel: self,
            i,
            wings: &s.wings,
            inherited,
            proven: &mut fan.proven,
            ranked: &mut s.ranked,
        };
        let Some((y, true)) = walk.choose(x, None) else {
            return fan;
        };
        let start = tri(i, x, y);
        fan.tris.push(start);
        let mut boundaries = 0;
        let (mut prev, mut cur) = (x, y);
        for _ in 0..s.wings.len() + 2 {
            match walk.choose(cur, Some(prev)) {
                Some((z, true)) => {
                    let t = tri(i, cur, z);
                    if fan.tris.contains(&t) {
                        fan.interior = true;
                        break;
                    }
                    fan.tris.push(t);
                    (prev, cur) = (cur, z);
                }
                _ => {
                    boundaries += 1;
                    if boundaries == 2 {
                        break;
                    }
                    (prev, cur) = (y, x);
                }
            }
        }
        fan
    }

    /// The nearest Delaunay neighbour of `i` (ties: smaller id).
    fn nearest(&self, i: u32, proven: &mut bool) -> Option<u32> {
        let x = self.near[i as usize];
        *proven &= self.nn_proven[i as usize];
        (x != INFINITE).then_some(x)
    }

    /// Whether some fan could select `t`: its circumradius is below its
    /// hole radius here. That radius bounds the whole cloud's from above
    /// even where it is not proven (the cloud has only more points, so
    /// nearest neighbours only nearer), so a triangle too large here is
    /// too large there.
    pub fn selectable(&self, t: [u32; 3]) -> bool {
        let delta = self.delta(t, &mut true);
        let [a, b, c] = t.map(|v| self.p(v));
        circumradius(a, b, c) < delta
    }

    /// The hole radius for triangle `t`.
    fn delta(&self, t: [u32; 3], proven: &mut bool) -> f64 {
        match self.hole {
            Hole::Absolute(d) => d,
            Hole::Local { multiple, .. } => {
                multiple
                    * t.iter()
                        .map(|&v| self.spacing(v, proven))
                        .fold(0.0, f64::max)
            }
        }
    }

    /// The spacing of sample `v` for [`Hole::Local`]; where it is not
    /// proven, an upper bound on the cloud's ([`spacing_bounds`]).
    fn spacing(&self, v: u32, proven: &mut bool) -> f64 {
        let x = self.near[v as usize];
        let known = self.nn_proven[v as usize] && (x == INFINITE || self.nn_proven[x as usize]);
        if !known {
            *proven = false;
            return self.spacing_bound[v as usize];
        }
        capped(
            self.nn[v as usize],
            (x != INFINITE).then(|| self.nn[x as usize]),
            self.hole.ceiling(),
        )
    }
}

impl Hole {
    /// The largest spacing a corner counts for (infinite for none).
    pub fn ceiling(&self) -> f64 {
        match self {
            Hole::Absolute(_) => f64::INFINITY,
            Hole::Local { ceiling, .. } => *ceiling,
        }
    }
}

/// A sample's spacing from its nearest-neighbour distance `nn` and its
/// nearest neighbour's own (if it has a neighbour): at most [`OUTLIER`]
/// times the neighbour's, and at most `ceiling`.
fn capped(nn: f64, neighbours: Option<f64>, ceiling: f64) -> f64 {
    neighbours.map_or(nn, |x| nn.min(OUTLIER * x)).min(ceiling)
}

/// Per vertex, an upper bound on its spacing ([`Hole::Local`]) in the whole
/// cloud. A vertex whose nearest distance is proven (`nn_proven`) has the
/// cloud's nearest neighbour, whose distance in the tile bounds its own.
/// Otherwise the region shows the points not loaded when it can: the
/// cloud's nearest distance, and the nearest neighbour's distance to the
/// nearest other point seen. When it cannot, the tile's nearest distance
/// is the bound, uncapped: the cloud's nearest neighbour may be a point
/// not seen, whose own spacing is unknown. Without the cap's bound, a
/// stray sample whose nearest neighbour lay outside its tile kept a hole
/// radius of 185 spacings and doubt ran 140 spacings into the tile.
pub fn spacing_bounds(
    points: &[DVec3],
    near: &[u32],
    nn: &[f64],
    nn_proven: &[bool],
    region: &Region,
    ceiling: f64,
) -> Vec<f64> {
    (0..points.len())
        .map(|v| {
            let x = near[v];
            let tile = (x != INFINITE).then(|| nn[x as usize]);
            if nn_proven[v] {
                return capped(nn[v], tile, ceiling);
            }
            match region.nearest_beyond(points[v], nn[v]) {
                None => capped(nn[v], None, ceiling),
                Some((d, None)) => capped(d, tile, ceiling),
                Some((d, Some(y))) => capped(d, Some(y), ceiling),
            }
        })
        .collect()
}

/// The state of one fan walk.
struct Walk<'a, 'b> {
    sel: &'a Selector<'a>,
    i: u32,
    wings: &'a [Wing],
    inherited: Option<&'b dyn Fn([u32; 3]) -> Membership>,
    proven: &'a mut bool,
    ranked: &'a mut Vec<(f64, u32, Wing, Membership)>,
}

impl Walk<'_, '_> {
    /// Step 2 or 3 of algorithm 1 on edge `(i, e)`: the candidate with the
    /// largest angle opposite the edge (among those at an obtuse dihedral
    /// angle to `(i, e, prev)` when given, and among the inherited ones if
    /// any), and whether its circumradius is below the hole radius.
    fn choose(&mut self, e: u32, prev: Option<u32>) -> Option<(u32, bool)> {
        let sel = self.sel;
        let (pi, pe) = (sel.p(self.i), sel.p(e));
        let side = |q: DVec3| across(pi, pe, q);
        let back = prev.map(|v| side(sel.p(v)));
        let candidates = self.wings.iter().filter_map(|w| {
            let z = if w.a == e {
                w.b
            } else if w.b == e {
                w.a
            } else {
                return None;
            };
            let obtuse = match back {
                Some(u) => prev != Some(z) && u.dot(side(sel.p(z))) < 0.0,
                None => true,
            };
            obtuse.then_some((z, w))
        });
        // Each candidate's membership in the first round, read once, in a
        // list the walk keeps (one allocation per fan step was 3 % of the
        // run).
        let ranks = sel.d.ranks();
        let cosine = |z: u32| {
            let (a, b) = (pi - sel.p(z), pe - sel.p(z));
            a.dot(b) / (a.length() * b.length())
        };
        let inherited = self.inherited;
        let i = self.i;
        let ranked = &mut *self.ranked;
        ranked.clear();
        ranked.extend(candidates.map(|(z, w)| {
            let m = inherited.map_or(Membership::Out, |f| f(tri(i, e, z)));
            (cosine(z), z, *w, m)
        }));
        ranked.sort_by(|a, b| {
            a.0.total_cmp(&b.0)
                .then(ranks[a.1 as usize].cmp(&ranks[b.1 as usize]))
        });
        // A candidate of unknown membership may be inherited in the cloud,
        // which leaves the step unproven unless an inherited candidate
        // outranks it (the cloud's choice is that one either way). Without
        // that exception, a stray sample's unproven fan unsettled every
        // step whose candidates reached it, 140 spacings into a tile.
        let best_in = ranked.iter().position(|c| c.3 == Membership::In);
        let unknown = ranked.iter().position(|c| c.3 == Membership::Unknown);
        if unknown.is_some_and(|u| best_in.is_none_or(|b| u < b)) {
            *self.proven = false;
        }
        if best_in.is_some() {
            ranked.retain(|c| c.3 == Membership::In);
        }
        // A tile's candidate shown not to be the cloud's is passed over
        // (a tile sees one only where the cloud's sphere reaches beyond
        // what it loaded).
        let mut k = 0;
        if !sel.region.is_everything() {
            match self.settle(e) {
                Some(w) => k = w,
                None => *self.proven = false,
            }
        }
        let &(_, z, _, _) = self.ranked.get(k)?;
        let delta = sel.delta([self.i, e, z], &mut true);
        Some((z, circumradius(pi, pe, sel.p(z)) < delta))
    }

    /// The whole cloud's choice among `ranked` (best first), when the tile
    /// is sure of it: its place in `ranked` (`ranked.len()`: none). The
    /// cloud's candidates among the loaded points are a subset of the
    /// tile's: those proven its own, none of those proven absent, perhaps
    /// some others. If the best of those not absent is proven it wins
    /// there too; otherwise the cloud's winner is one of the candidates up
    /// to the first proven one, and the outcome is still certain when none
    /// of them could be selected (a boundary either way; the first stands
    /// for them all). A candidate the tile cannot see (its apex not
    /// loaded) could outrank them all: each outcome holds only when the
    /// region holds every point that could ([`Walk::unseen_cannot`]).
    fn settle(&self, e: u32) -> Option<usize> {
        let sel = self.sel;
        let mut first = None;
        for (k, &(cos, z, ref w, _)) in self.ranked.iter().enumerate() {
            let proof = sel.region.triangle(sel.d, self.i, w);
            if proof == Proof::Absent {
                continue;
            }
            let best = *first.get_or_insert(k);
            if proof == Proof::Held && k == best {
                // The winner is certain; so must be its hole radius.
                let mut known = true;
                let delta = sel.delta(tri(self.i, e, z), &mut known);
                let [p, q, r] = [self.i, e, z].map(|v| sel.p(v));
                let boundary = circumradius(p, q, r) >= delta;
                return (known && self.unseen_cannot(e, Some(cos), boundary)).then_some(k);
            }
            if sel.selectable(tri(self.i, e, z)) {
                return None;
            }
            if proof == Proof::Held {
                return self.unseen_cannot(e, Some(cos), true).then_some(best);
            }
        }
        self.unseen_cannot(e, None, true)
            .then_some(first.unwrap_or(self.ranked.len()))
    }

    /// Whether every point that could make an unseen candidate on edge
    /// `(i, e)` change the outcome was loaded. With `Some(cos)`, it would
    /// have to see the edge under an angle at least that large (the
    /// ranking is by that angle): such points lie in the spindle of the
    /// inscribed angle, within `(L / 2) max(1, cot(angle / 2))` of the
    /// edge's midpoint (`L` its length). When the outcome is a `boundary` (no
    /// candidate selectable), it would also have to be selectable: its
    /// triangle's circumradius below its hole radius, so it lies within
    /// twice that of the midpoint. Deviation from a full proof, named: the
    /// radius taken is the edge's own (its corners' spacings); an unseen
    /// point sparser than both corners has a larger one. Bounding that by
    /// the largest hole radius (40 median spacings) left fans near every
    /// face unproven, and their doubt, carried by inheritance, crossed the
    /// whole 1M dragon.
    fn unseen_cannot(&self, e: u32, cos: Option<f64>, boundary: bool) -> bool {
        let sel = self.sel;
        let (a, b) = (sel.p(self.i), sel.p(e));
        let half = 0.5 * a.distance(b);
        let spindle = cos.map_or(f64::INFINITY, |c| spindle_reach(half, c));
        let selectable = match boundary {
            true => 2.0 * sel.delta([self.i, e, e], &mut true) + half,
            false => f64::INFINITY,
        };
        let reach = spindle.min(selectable);
        reach.is_finite() && sel.region.holds_ball(a.midpoint(b), reach)
    }
}

/// How far from the midpoint of a segment of half-length `half` a point
/// can lie that sees it under an angle whose cosine is at most `cos`: the
/// spindle of that inscribed angle reaches `half * cot(angle / 2)`, and
/// for an obtuse angle the lens still reaches the segment's ends.
fn spindle_reach(half: f64, cos: f64) -> f64 {
    half * ((1.0 + cos) / (1.0 - cos)).sqrt().max(1.0)
}

/// Circumradius of a triangle (infinite when degenerate).
pub fn circumradius(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let (u, v) = (b - a, c - a);
    let area2 = u.cross(v).length();
    if area2 == 0.0 {
        return f64::INFINITY;
    }
    u.length() * v.length() * (u - v).length() / (2.0 * area2)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    /// Every point that sees a segment under at least an angle lies within
    /// the spindle's reach of its midpoint, and the reach is attained:
    /// random points against the angle they see, brute force.
    #[test]
    fn points_seeing_a_segment_wider_lie_within_the_spindle() {
        let mut rng = Rng::new(5);
        let (a, b) = (DVec3::new(-1.0, 0.0, 0.0), DVec3::new(1.0, 0.0, 0.0));
        let mut closest: f64 = f64::INFINITY;
        for _ in 0..100_000 {
            let z = rng.unit_vector() * rng.range(0.0, 8.0);
            let (u, v) = (a - z, b - z);
            let cos = u.dot(v) / (u.length() * v.length());
            let reach = spindle_reach(1.0, cos);
            assert!(z.length() <= reach * (1.0 + 1e-12), "{z} {cos}");
            closest = closest.min(reach - z.length());
        }
        assert!(closest < 1e-2, "{closest}");
        assert_eq!(spindle_reach(1.0, 0.0), 1.0);
        assert_eq!(spindle_reach(1.0, -0.5), 1.0);
    }
}
