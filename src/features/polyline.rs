//! Polyline growth (paper 5 section 5, after Lee's curve reconstruction):
//! the smoothed edge points of one kind go into a priority queue by their
//! distance to the nearest corner, farthest first; from the first point
//! left, its neighbours within `gamma_max` get a PCA axis, the two
//! neighbours projecting farthest along it become growth points and every
//! neighbour leaves the queue; each growth point then takes the points left
//! within `gamma_max`, and the one projecting farthest ahead (away from the
//! previous growth point) is the next; a line ends where no point is left
//! ahead. Growth points are the polyline's vertices.
//!
//! Deviation, named: the distance to the nearest corner is capped
//! ([`super::params::Resolved::corner_cap`]), so a point's priority depends
//! only on its surroundings (ties: input id); beyond the cap the order no
//! longer keeps growth away from corners, which is its purpose.

use super::refine::refine_lines;
use super::smooth::elongation;
use crate::spatial::BallGrid;
use crate::spatial::Neighbour;
use glam::DVec3;

/// Grows the polylines through `points` (tie keys `ids`) with radius
/// `gamma`, seeds ordered by `priority` (higher first; ties by id).
/// Returns each polyline's vertices, in growth order from one end, each
/// vertex refined across the line (`refine.rs`; `refine.0` the radius,
/// 0 for none, `refine.1` the width).
pub fn grow_polylines(
    points: &[DVec3],
    ids: &[u64],
    priority: &[f64],
    gamma: f64,
    refine: (f64, f64),
) -> Vec<Vec<DVec3>> {
    let Some(grid) = BallGrid::new(points, ids, gamma) else {
        return Vec::new();
    };
    let mut order: Vec<usize> = (0..points.len()).collect();
    order.sort_by(|&a, &b| {
        priority[b]
            .total_cmp(&priority[a])
            .then(ids[a].cmp(&ids[b]))
    });
    let mut g = Growth {
        grid: &grid,
        points,
        gamma,
        used: vec![false; points.len()],
        found: Vec::new(),
    };
    let mut lines = Vec::new();
    for seed in order {
        if g.used[seed] {
            continue;
        }
        let start = points[seed];
        let hood = g.take(start);
        let Some((axis, lo, hi)) = g.extremes(start, &hood, None) else {
            continue;
        };
        let mut back = g.extend(lo, start);
        let ahead = g.extend(hi, start);
        back.reverse();
        back.push(start);
        back.extend(ahead);
        let _ = axis;
        if back.len() >= 2 {
            lines.push(back);
        }
    }
    refine_lines(&mut lines, &grid, refine.0, refine.1);
    lines
}

struct Growth<'a> {
    grid: &'a BallGrid<'a>,
    points: &'a [DVec3],
    gamma: f64,
    used: Vec<bool>,
    found: Vec<Neighbour>,
}

impl Growth<'_> {
    /// The unused points within `gamma` of `at`, now used, in (distance,
    /// id) order.
    fn take(&mut self, at: DVec3) -> Vec<usize> {
        self.grid.within(at, self.gamma, None, &mut self.found);
        let mut out = Vec::new();
        for n in &self.found {
            let j = n.index as usize;
            if !self.used[j] {
                self.used[j] = true;
                out.push(j);
            }
        }
        out
    }

    /// The PCA axis of `hood` (with `at`), and the two extreme projections
    /// of the hood onto the line through `at` along it (the paper's new
    /// growth points); the axis turned to agree with `ahead` if given.
    /// `None` for an empty hood.
    fn extremes(
        &self,
        at: DVec3,
        hood: &[usize],
        ahead: Option<DVec3>,
    ) -> Option<(DVec3, DVec3, DVec3)> {
        if hood.is_empty() {
            return None;
        }
        let mut pts: Vec<DVec3> = hood.iter().map(|&j| self.points[j]).collect();
        pts.push(at);
        let (_, mut axis, centre) = elongation(&pts);
        if ahead.is_some_and(|a| axis.dot(a) < 0.0) {
            axis = -axis;
        }
        let t = hood.iter().map(|&j| (self.points[j] - centre).dot(axis));
        let t0 = (at - centre).dot(axis);
        let (lo, hi) = t.fold((t0, t0), |(lo, hi), t| (lo.min(t), hi.max(t)));
        Some((axis, centre + axis * lo, centre + axis * hi))
    }

    /// The growth points after `g` (reached from `prev`), in order; empty
    /// when `g` is `prev` (nothing on that side).
    fn extend(&mut self, mut g: DVec3, mut prev: DVec3) -> Vec<DVec3> {
        let mut line = Vec::new();
        if g == prev {
            return line;
        }
        line.push(g);
        loop {
            let hood = self.take(g);
            let Some((_, _, next)) = self.extremes(g, &hood, Some(g - prev)) else {
                return line;
            };
            if (next - g).dot(g - prev) <= 0.0 {
                return line;
            }
            line.push(next);
            prev = g;
            g = next;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    #[test]
    fn points_along_a_curve_give_one_polyline_spanning_it() {
        let mut rng = Rng::new(6);
        let pts: Vec<DVec3> = (0..400)
            .map(|_| {
                let t = rng.range(0.0, 3.0);
                DVec3::new(t, 0.2 * (t * 2.0).sin(), 0.0) + rng.gaussian_vector(0.003)
            })
            .collect();
        let ids: Vec<u64> = (0..400).collect();
        let prio = vec![0.0; 400];
        let lines = grow_polylines(&pts, &ids, &prio, 0.1, (0.0, 0.0));
        assert_eq!(lines.len(), 1, "{} lines", lines.len());
        let l = &lines[0];
        let xs: Vec<f64> = l.iter().map(|p| p.x).collect();
        let (lo, hi) = xs
            .iter()
            .fold((9.0f64, -9.0f64), |(a, b), x| (a.min(*x), b.max(*x)));
        assert!(lo < 0.1 && hi > 2.9, "{lo} .. {hi}");
        let steps: Vec<f64> = l.windows(2).map(|w| w[0].distance(w[1])).collect();
        let mean = steps.iter().sum::<f64>() / steps.len() as f64;
        assert!(steps.iter().all(|s| *s <= 0.11), "{steps:?}");
        assert!(mean > 0.05, "mean step {mean}");
    }
}
