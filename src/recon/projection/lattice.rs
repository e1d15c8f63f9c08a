//! The lattice the local projection grows in, so that a tiled run equals an
//! untiled one: greedy growth depends on where it starts and which order
//! its front takes, so it must never start or stop where a *tile* ends.
//! It runs instead as jobs on a lattice of side `cell` anchored at the
//! store origin (which no tiling moves), in four levels:
//!
//! - level 0, a cell: its points at least `band` from every lattice plane;
//! - level 1, a face: points within `band + overlap` of one plane, at
//!   least that far from the others (the strip along a face, less its
//!   ends);
//! - level 2, an edge: within `band + 2 overlap` of two planes;
//! - level 3, a corner: within `band + 3 overlap` of three planes.
//!
//! A job's *window* is that set of positions: a box. A job keeps only
//! triangles whose three vertices lie in its window; it grows a little
//! beyond (`spill`) and reads the points of its *view* (grown by `view`
//! more), with the lower levels' triangles there as they are (their open
//! vertices the front). Windows of
//! one level are disjoint (a plane axis of one is a cell axis of the
//! other, `half(level)` apart), so the jobs of a level neither meet nor
//! read each other and run in any order, or in parallel; a job reads only
//! lower levels within a cell of itself. Each level's windows overlap the
//! lower levels' by `overlap`, so a triangle up to that size across the
//! line where a lower level stopped can still be made. Every point lies in
//! some window (the levels' half-widths grow, see [`Lattice::job_of`]).

use crate::geom::Aabb;
use glam::DVec3;

/// Levels: cell, face, edge, corner.
pub const LEVELS: u8 = 4;

/// One job: `planes` has bit `a` set when axis `a` is a plane axis (`n[a]`
/// names the plane at `n[a] * cell`); otherwise `n[a]` names the cell
/// `[n[a] * cell, (n[a] + 1) * cell)`. Ordered by level first: the order
/// jobs run and are written in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct JobKey {
    pub level: u8,
    pub planes: u8,
    pub n: [i64; 3],
}

/// Sizes of the lattice, absolute (store units).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Lattice {
    pub cell: f64,
    pub band: f64,
    pub overlap: f64,
    /// How far beyond its window a job grows (triangles it then drops:
    /// the ones it keeps are those an unbounded growth made, not the
    /// slivers of a growth fenced in at its window's edge).
    pub spill: f64,
    /// How far beyond its spill a job sees.
    pub view: f64,
}

impl Lattice {
    /// Half-width of a level's windows across its plane axes (and their
    /// distance from the planes along the others).
    pub fn half(&self, level: u8) -> f64 {
        self.band + f64::from(level) * self.overlap
    }

    /// The job of `level` whose window holds `p`, if any. Every point has
    /// one at some level: with `f(l)` the number of axes within `half(l)`
    /// of a plane, non-decreasing in `l` and at most 3, some `l` has
    /// `f(l) == l`.
    pub fn job_of(&self, p: DVec3, level: u8) -> Option<JobKey> {
        let h = self.half(level);
        let mut planes = 0u8;
        let mut n = [0i64; 3];
        for a in 0..3 {
            let x = p[a] / self.cell;
            let plane = x.round();
            if (p[a] - plane * self.cell).abs() < h {
                planes |= 1 << a;
                n[a] = plane as i64;
            } else {
                n[a] = x.floor() as i64;
            }
        }
        (planes.count_ones() == u32::from(level)).then_some(JobKey { level, planes, n })
    }

    /// Whether `p` lies in `key`'s window.
    pub fn in_window(&self, key: JobKey, p: DVec3) -> bool {
        self.job_of(p, key.level) == Some(key)
    }

    /// The closed box around `key`'s window.
    pub fn window(&self, key: JobKey) -> Aabb {
        let h = self.half(key.level);
        let (mut min, mut max) = (DVec3::ZERO, DVec3::ZERO);
        for a in 0..3 {
            let at = key.n[a] as f64 * self.cell;
            if key.planes & (1 << a) != 0 {
                (min[a], max[a]) = (at - h, at + h);
            } else {
                (min[a], max[a]) = (at + h, at + self.cell - h);
            }
        }
        Aabb::new(min, max)
    }

    /// Where `key` grows: its window grown by `spill`.
    pub fn grow_box(&self, key: JobKey) -> Aabb {
        grown(self.window(key), self.spill)
    }

    /// What `key` reads: its window grown by `spill + view`.
    pub fn view_box(&self, key: JobKey) -> Aabb {
        grown(self.window(key), self.spill + self.view)
    }

    /// The lattice point a job belongs to (a tile owns the jobs whose
    /// anchor lies in its core).
    pub fn anchor(&self, key: JobKey) -> DVec3 {
        DVec3::new(key.n[0] as f64, key.n[1] as f64, key.n[2] as f64) * self.cell
    }

    /// The jobs of `level` whose windows may meet the box `b` (a superset
    /// by rounding at most), in key order.
    pub fn jobs_meeting(&self, level: u8, b: &Aabb) -> Vec<JobKey> {
        let (h, c) = (self.half(level), self.cell);
        let mut out = Vec::new();
        for planes in 0u8..8 {
            if planes.count_ones() != u32::from(level) {
                continue;
            }
            let mut range = [(0i64, 0i64); 3];
            for (a, r) in range.iter_mut().enumerate() {
                *r = if planes & (1 << a) != 0 {
                    (
                        ((b.min[a] - h) / c).ceil() as i64,
                        ((b.max[a] + h) / c).floor() as i64,
                    )
                } else {
                    (
                        ((b.min[a] + h) / c).floor() as i64,
                        ((b.max[a] - h) / c).floor() as i64,
                    )
                };
            }
            for x in range[0].0..=range[0].1 {
                for y in range[1].0..=range[1].1 {
                    for z in range[2].0..=range[2].1 {
                        out.push(JobKey {
                            level,
                            planes,
                            n: [x, y, z],
                        });
                    }
                }
            }
        }
        out.sort_unstable();
        out
    }
}

fn grown(b: Aabb, by: f64) -> Aabb {
    Aabb::new(b.min - DVec3::splat(by), b.max + DVec3::splat(by))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lattice() -> Lattice {
        Lattice {
            cell: 48.0,
            band: 4.0,
            overlap: 4.0,
            spill: 4.0,
            view: 10.0,
        }
    }

    /// Seeded points over a few cells, with their job at every level.
    fn samples() -> Vec<DVec3> {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        (0..20_000)
            .map(|_| DVec3::new(next(), next(), next()) * 150.0 - DVec3::splat(40.0))
            .collect()
    }

    #[test]
    fn every_point_has_a_window_and_windows_of_a_level_are_apart() {
        let lat = lattice();
        let pts = samples();
        for p in &pts {
            assert!((0..LEVELS).any(|l| lat.job_of(*p, l).is_some()), "{p}");
        }
        // Two points in different windows of one level are at least the
        // windows' gap apart along some axis (0 here: they may touch, never
        // overlap), and each window's box holds its points.
        for l in 0..LEVELS {
            let keyed: Vec<(JobKey, DVec3)> = pts
                .iter()
                .filter_map(|p| lat.job_of(*p, l).map(|k| (k, *p)))
                .collect();
            for &(k, p) in &keyed {
                let w = lat.window(k);
                assert!(p.cmpge(w.min).all() && p.cmple(w.max).all());
                assert!(lat.jobs_meeting(l, &Aabb::new(p, p)).contains(&k));
            }
            for (i, &(k, p)) in keyed.iter().enumerate().step_by(97) {
                for &(k2, _) in keyed.iter().skip(i + 1).step_by(13) {
                    if k2 != k {
                        let (a, b) = (lat.window(k), lat.window(k2));
                        let apart = (0..3).any(|x| a.max[x] <= b.min[x] || b.max[x] <= a.min[x]);
                        assert!(apart, "{k:?} {k2:?} at {p}");
                    }
                }
            }
        }
    }
}
