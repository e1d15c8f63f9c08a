//! Enhancement of one potential feature point (paper 5 section 3): its
//! feature neighbours within `phi`, projected into its support plane as 2-D
//! points `q_j` weighted by their curvature magnitude, are grouped into
//! curve-fitting sets by region growing with the "growth circle"; each set
//! of enough points gets a weighted quadratic curve ([`super::curve`]);
//! the point moves onto the nearest curve (an edge point), and where two or
//! more curves pass, their crossing nearest to it becomes a corner.
//!
//! The growth circle around a growth point `A` with previous growth point
//! `B` (radius `R`, angle `alpha = pi/3`) is split by the axis `AB` into
//! three regions; Fig. 6 of the paper is not in our copy, so we read the
//! text as: the *new-growth* region ahead of `A` (within `alpha` of the
//! direction away from `B`), the *near* region behind it (within `alpha` of
//! the direction toward `B`), and the *crossing* region on both sides
//! (around `Perp(AB)`). Rules 1-3 of the text then apply: the crossing
//! region's two points farthest along `Perp(AB)` with weight above `kappa`
//! are the growth points of a crossing curve (which we grow next, before
//! any new seed); the new-growth region's heaviest point above `kappa` is
//! the next growth point, and its points join the set; the near region's
//! points join the set. `kappa` is the local set's mean weight (the text's
//! "locally adaptive" choice).

use super::curve::Curve;
use glam::DVec2;

/// Smallest angle at which two potential lines make a corner (30 degrees;
/// see [`Curve::crossing`]).
pub const MIN_CROSSING: f64 = std::f64::consts::PI / 6.0;

/// Thresholds of one enhancement.
#[derive(Clone, Copy, Debug)]
pub struct EnhanceParams {
    /// Growth-circle radius `R`.
    pub radius: f64,
    /// Growth-circle sector angle `alpha`.
    pub sector: f64,
    /// Fewest points a curve-fitting set keeps.
    pub min_points: usize,
    /// How elongated a set must be to make a curve: `(l0 - l1) / (l0 + l1)`
    /// of its weighted 2-D covariance, the smoothing's correlation test
    /// (section 4, see `smooth.rs`). Deviation: the paper fits every set
    /// big enough; a blob of a few heavy points at the edge of a wide band
    /// then gets a curve of arbitrary direction, which crosses the real
    /// one and makes a corner out of nothing.
    pub elongation: f64,
}

/// What the enhancement makes of a point, in its support plane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Enhanced2 {
    /// The point projected onto its nearest potential feature line.
    pub edge: DVec2,
    /// That line's unit tangent at `edge`.
    pub tangent: DVec2,
    /// Where two potential lines cross, nearest to the point, if any.
    pub corner: Option<DVec2>,
}

/// Enhances the point at `at` given its local set `q` (weights `w`,
/// positive); `None` when no potential feature line passes (not a feature
/// point).
pub fn enhance(q: &[DVec2], w: &[f64], at: DVec2, p: &EnhanceParams) -> Option<Enhanced2> {
    let curves = distinct_curves(q, w, curve_sets(q, w, p), p);
    let (edge, tangent) = curves.iter().map(|c| c.nearest(at)).min_by(|a, b| {
        a.0.distance_squared(at)
            .total_cmp(&b.0.distance_squared(at))
    })?;
    let mut corner: Option<DVec2> = None;
    for (i, a) in curves.iter().enumerate() {
        for b in &curves[i + 1..] {
            if let Some(c) = a.crossing(b, p.radius, MIN_CROSSING, at) {
                if corner.is_none_or(|k| c.distance_squared(at) < k.distance_squared(at)) {
                    corner = Some(c);
                }
            }
        }
    }
    Some(Enhanced2 {
        edge,
        tangent,
        corner,
    })
}

/// The curves of the sets that make one: enough points, elongated, long
/// enough, and not a piece of a heavier set's line.
///
/// Deviations, named (with `elongation`): a set shorter than the growth
/// circle's radius never grew (a leftover blob at the edge of a band,
/// whose quadratic bends anywhere); and a set whose points mostly lie
/// within `R / 2` of a heavier set's curve (extended by `R` at its ends) is
/// a strip or a continuation of the same wide band that the growth left. The paper fits both; their curves cross
/// the real one at random angles, and every crossing is a corner out of
/// nothing (measured on a stepped block: 96 corners, 80 of them more than
/// 10 sp from any vertex of the block).
fn distinct_curves(
    q: &[DVec2],
    w: &[f64],
    mut sets: Vec<Vec<usize>>,
    p: &EnhanceParams,
) -> Vec<Curve> {
    let weight = |s: &Vec<usize>| s.iter().map(|&j| w[j]).sum::<f64>();
    sets.retain(|s| s.len() >= p.min_points);
    // Heaviest first (stable: ties keep growth order).
    sets.sort_by(|a, b| weight(b).total_cmp(&weight(a)));
    let near = p.radius * 0.5;
    let mut kept: Vec<Curve> = Vec::new();
    for s in &sets {
        let Some(c) = Curve::fit(q, w, s, p.elongation) else {
            continue;
        };
        if c.hi - c.lo < p.radius {
            continue;
        }
        let along = s
            .iter()
            .filter(|&&j| {
                kept.iter()
                    .any(|k| k.nearest_within(q[j], p.radius).0.distance(q[j]) <= near)
            })
            .count();
        if 2 * along <= s.len() {
            kept.push(c);
        }
    }
    kept
}

/// Growth state over the local set.
struct Grower<'a> {
    q: &'a [DVec2],
    w: &'a [f64],
    kappa: f64,
    r2: f64,
    cos2_sector: f64,
    assigned: Vec<bool>,
    /// Growth-point pairs of crossing curves, to grow before new seeds.
    crossing: Vec<(usize, usize)>,
    /// Reused by every step (a step allocated three vectors: 4 % of the
    /// dragon's run went to the allocator).
    spare: Regions,
}

/// The circle around `a` split by the growth direction `ahead`.
#[derive(Default)]
struct Regions {
    ahead: Vec<usize>,
    behind: Vec<usize>,
    side: Vec<usize>,
}

impl Grower<'_> {
    /// Unassigned points within `R` of point `a` (itself excluded), by
    /// region relative to the unit direction `ahead`.
    fn regions(&self, a: usize, ahead: DVec2, r: &mut Regions) {
        r.ahead.clear();
        r.behind.clear();
        r.side.clear();
        let pa = self.q[a];
        for (j, &qj) in self.q.iter().enumerate() {
            if j == a || self.assigned[j] {
                continue;
            }
            let d = qj - pa;
            let len2 = d.length_squared();
            if len2 > self.r2 {
                continue;
            }
            // The cosine to `ahead` against the sector's, squared (no root).
            let along = d.dot(ahead);
            let steep = along * along >= self.cos2_sector * len2 && len2 > 0.0;
            if steep && along > 0.0 {
                r.ahead.push(j);
            } else if steep || len2 == 0.0 {
                r.behind.push(j);
            } else {
                r.side.push(j);
            }
        }
    }

    /// The heaviest of `set` above `kappa` (the first on ties: local sets
    /// come in a canonical order, `spatial::ball`).
    fn heaviest(&self, set: &[usize]) -> Option<usize> {
        self.heaviest_of(set.iter().copied())
    }

    /// [`Grower::heaviest`] over any sequence of indices.
    fn heaviest_of(&self, set: impl Iterator<Item = usize>) -> Option<usize> {
        set.filter(|&j| self.w[j] > self.kappa)
            .fold(None, |best: Option<usize>, j| match best {
                Some(b) if self.w[b] >= self.w[j] => Some(b),
                _ => Some(j),
            })
    }

    /// Rule 1: the crossing region's two points farthest along `perp`.
    fn note_crossing(&mut self, a: usize, perp: DVec2, side: &[usize]) {
        let heavy: Vec<usize> = side
            .iter()
            .copied()
            .filter(|&j| self.w[j] > self.kappa)
            .collect();
        let along = |j: usize| (self.q[j] - self.q[a]).dot(perp);
        let lo = heavy
            .iter()
            .copied()
            .min_by(|&x, &y| along(x).total_cmp(&along(y)));
        let hi = heavy
            .iter()
            .copied()
            .max_by(|&x, &y| along(x).total_cmp(&along(y)));
        if let (Some(lo), Some(hi)) = (lo, hi) {
            if lo != hi {
                self.crossing.push((lo, hi));
            }
        }
    }

    /// One application of the growth-circle rule at growth point `g` whose
    /// previous growth point is `prev`: adds the near and new-growth points
    /// to `set`, returns the next growth point.
    fn step(&mut self, g: usize, prev: usize, set: &mut Vec<usize>) -> Option<usize> {
        let ahead = (self.q[g] - self.q[prev]).try_normalize()?;
        let mut r = std::mem::take(&mut self.spare);
        self.regions(g, ahead, &mut r);
        self.note_crossing(g, ahead.perp(), &r.side);
        let next = self.heaviest(&r.ahead);
        for &j in r.ahead.iter().chain(&r.behind) {
            self.assigned[j] = true;
            set.push(j);
        }
        self.spare = r;
        next
    }

    /// Grows from growth point `g` away from `prev` until no growth point
    /// is left.
    fn grow(&mut self, mut g: usize, mut prev: usize, set: &mut Vec<usize>) {
        while let Some(next) = self.step(g, prev, set) {
            prev = g;
            g = next;
        }
    }

    /// How the next curve starts, with its first set members; `None`
    /// when no seed is left.
    fn start(&mut self) -> Option<(Start, Vec<usize>)> {
        while let Some((a, b)) = self.crossing.pop() {
            if !self.assigned[a] && !self.assigned[b] {
                self.assigned[a] = true;
                self.assigned[b] = true;
                return Some((Start::Pair(a, b), vec![a, b]));
            }
        }
        let seed = self.heaviest_of((0..self.q.len()).filter(|&j| !self.assigned[j]))?;
        self.assigned[seed] = true;
        let mut set = vec![seed];
        // B: the heaviest other point of the circle (any weight).
        let mut around = std::mem::take(&mut self.spare);
        self.regions(seed, DVec2::X, &mut around);
        let all = around
            .ahead
            .iter()
            .chain(&around.behind)
            .chain(&around.side);
        let Some(b) = all
            .copied()
            .fold(None, |best: Option<usize>, j| match best {
                Some(x) if self.w[x] >= self.w[j] => Some(x),
                _ => Some(j),
            })
        else {
            self.spare = around;
            return Some((Start::Lone, set));
        };
        self.spare = around;
        self.assigned[b] = true;
        set.push(b);
        // Around the seed A, ahead is away from B; B is G1, the new-growth
        // region's heaviest point G2.
        let g2 = self.step(seed, b, &mut set);
        Some((Start::Seed { a: seed, b, g2 }, set))
    }
}

/// How a curve starts.
enum Start {
    /// A crossing curve's two growth points: grow each away from the other.
    Pair(usize, usize),
    /// Seed `A` with `G1 = B` and `G2` ahead of `A`: grow both away from `A`.
    Seed {
        a: usize,
        b: usize,
        g2: Option<usize>,
    },
    /// A seed with nothing around it.
    Lone,
}

/// The curve-fitting sets of the local set (section 3's preprocessing).
pub(crate) fn curve_sets(q: &[DVec2], w: &[f64], p: &EnhanceParams) -> Vec<Vec<usize>> {
    if q.is_empty() {
        return Vec::new();
    }
    let kappa = w.iter().sum::<f64>() / w.len() as f64;
    let mut g = Grower {
        q,
        w,
        kappa,
        r2: p.radius * p.radius,
        cos2_sector: p.sector.cos() * p.sector.cos(),
        assigned: vec![false; q.len()],
        crossing: Vec::new(),
        spare: Regions::default(),
    };
    let mut sets = Vec::new();
    while let Some((start, mut set)) = g.start() {
        match start {
            Start::Pair(x, y) => {
                g.grow(x, y, &mut set);
                g.grow(y, x, &mut set);
            }
            Start::Seed { a, b, g2 } => {
                g.grow(b, a, &mut set);
                if let Some(g2) = g2 {
                    g.grow(g2, a, &mut set);
                }
            }
            Start::Lone => {}
        }
        sets.push(set);
    }
    sets
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    fn params() -> EnhanceParams {
        EnhanceParams {
            radius: 0.3,
            sector: std::f64::consts::PI / 3.0,
            min_points: 5,
            elongation: 0.6,
        }
    }

    /// A band of points around `y = 0.1 x^2 + 0.2`, heavier near its centre.
    fn band(rng: &mut Rng, n: usize) -> (Vec<DVec2>, Vec<f64>) {
        let mut q = Vec::new();
        let mut w = Vec::new();
        for _ in 0..n {
            let x = rng.range(-1.5, 1.5);
            let off = rng.range(-0.3, 0.3);
            q.push(DVec2::new(x, 0.1 * x * x + 0.2 + off));
            w.push(1.0 - off.abs() * 2.0);
        }
        (q, w)
    }

    #[test]
    fn a_band_gives_one_curve_through_its_heavy_middle() {
        let mut rng = Rng::new(4);
        let (q, w) = band(&mut rng, 300);
        let e = enhance(&q, &w, DVec2::new(0.0, 0.0), &params()).unwrap();
        assert!(
            (e.edge - DVec2::new(0.0, 0.2)).length() < 0.05,
            "{:?}",
            e.edge
        );
        assert!(e.corner.is_none(), "{e:?}");
    }

    #[test]
    fn two_crossing_bands_give_a_corner() {
        let mut rng = Rng::new(8);
        let mut q = Vec::new();
        let mut w = Vec::new();
        for k in 0..400 {
            let t = rng.range(-1.5, 1.5);
            let off = rng.range(-0.15, 0.15);
            let p = if k % 2 == 0 {
                DVec2::new(t, off)
            } else {
                DVec2::new(off, t)
            };
            q.push(p);
            w.push(1.0 - off.abs() * 3.0);
        }
        let e = enhance(&q, &w, DVec2::new(0.3, 0.05), &params()).unwrap();
        let c = e.corner.expect("a corner where the bands cross");
        assert!(c.length() < 0.1, "{c}");
        assert!(
            (e.edge - DVec2::new(0.3, 0.0)).length() < 0.08,
            "{:?}",
            e.edge
        );
    }

    #[test]
    fn scattered_points_give_no_curve_or_noise_only() {
        assert!(enhance(&[], &[], DVec2::ZERO, &params()).is_none());
        let q = [DVec2::ZERO, DVec2::X];
        assert!(enhance(&q, &[1.0, 1.0], DVec2::ZERO, &params()).is_none());
    }
}
