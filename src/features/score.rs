//! Scoring extracted feature lines against true ones, per kind: recall is
//! the share of true line length within `tolerance` of an extracted line
//! of the kind, precision the share of extracted length within
//! `tolerance` of a true line of the kind, both measured on samples taken
//! every `step` along the lines (the protocol: 1 sp and 0.25 sp).

use super::lines::LineGraph;
use super::seams::segment_distance;
use crate::geom::LineKind;
use crate::synth::TrueSegment;
use glam::DVec3;
use std::collections::HashMap;

/// Recall and precision of one kind (`None` when there is no length to
/// measure on that side).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KindScore {
    /// Share of the true length found within the tolerance (`None` without true lines).
    pub recall: Option<f64>,
    /// Share of the found length within the tolerance of a true line (`None` without found lines).
    pub precision: Option<f64>,
    /// Length of the true lines of this kind.
    pub true_length: f64,
    /// Length of the found lines of this kind.
    pub found_length: f64,
}

/// Scores `found` against `truth` for ridges and valleys, in that order.
pub fn score(
    found: &LineGraph,
    truth: &[TrueSegment],
    tolerance: f64,
    step: f64,
) -> [KindScore; 2] {
    [LineKind::Ridge, LineKind::Valley].map(|kind| {
        let t: Vec<(DVec3, DVec3)> = truth
            .iter()
            .filter(|s| s.kind == kind)
            .map(|s| (s.a, s.b))
            .collect();
        let f: Vec<(DVec3, DVec3)> = found
            .edges
            .iter()
            .filter(|e| e.2 == kind)
            .map(|e| (found.vertices[e.0 as usize], found.vertices[e.1 as usize]))
            .collect();
        KindScore {
            recall: covered(&t, &f, tolerance, step),
            precision: covered(&f, &t, tolerance, step),
            true_length: t.iter().map(|s| s.0.distance(s.1)).sum(),
            found_length: f.iter().map(|s| s.0.distance(s.1)).sum(),
        }
    })
}

/// Share of the samples along `lines` (every `step`) within `tol` of a
/// segment of `other`.
fn covered(lines: &[(DVec3, DVec3)], other: &[(DVec3, DVec3)], tol: f64, step: f64) -> Option<f64> {
    let index = SegmentGrid::new(other, tol);
    let (mut near, mut all) = (0u64, 0u64);
    for &(a, b) in lines {
        let n = (a.distance(b) / step).ceil().max(1.0) as usize;
        // Sample midpoints of n equal pieces: each stands for one piece.
        for k in 0..n {
            let p = a + (b - a) * ((k as f64 + 0.5) / n as f64);
            all += 1;
            near += u64::from(index.within(p, tol));
        }
    }
    (all > 0).then(|| near as f64 / all as f64)
}

/// Where the missed length of one side lies: `counts[e][n]` counts the
/// samples (each `step` long) not within `tol` of the other side, by their
/// distance to the nearest end of their own segment (`e`: below 1, 2, 4, 8
/// tolerances, beyond) and to the nearest segment of the other side (`n`:
/// below 2, 4 tolerances, beyond); `other_kind` counts the missed samples
/// within `tol` of a line of the other kind.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Misses {
    /// `counts[e][n]`: missed samples by distance class to their own segment's end (`e`) and to the other side (`n`).
    pub counts: [[u64; 3]; 5],
    /// Missed samples within the tolerance of a line of the other kind.
    pub other_kind: u64,
    /// Samples taken on the true lines.
    pub samples: u64,
}

/// The end-distance bucket bounds of [`Misses`], in tolerances.
pub const END_BUCKETS: [f64; 4] = [1.0, 2.0, 4.0, 8.0];

/// [`Misses`] of `lines` against `other` (same kind) and `wrong` (the
/// other kind), sampled as [`score`] does.
pub fn misses(
    lines: &[(DVec3, DVec3)],
    other: &[(DVec3, DVec3)],
    wrong: &[(DVec3, DVec3)],
    tol: f64,
    step: f64,
) -> Misses {
    let near = SegmentGrid::new(other, 4.0 * tol);
    let wrong = SegmentGrid::new(wrong, tol);
    let mut m = Misses::default();
    for &(a, b) in lines {
        let len = a.distance(b);
        let n = (len / step).ceil().max(1.0) as usize;
        for k in 0..n {
            let t = (k as f64 + 0.5) / n as f64;
            let p = a + (b - a) * t;
            m.samples += 1;
            let d = near.nearest(p).unwrap_or(f64::INFINITY);
            if d <= tol {
                continue;
            }
            let to_end = len * t.min(1.0 - t);
            let e = END_BUCKETS
                .iter()
                .position(|b| to_end < b * tol)
                .unwrap_or(END_BUCKETS.len());
            let nb = if d <= 2.0 * tol {
                0
            } else if d <= 4.0 * tol {
                1
            } else {
                2
            };
            m.counts[e][nb] += 1;
            m.other_kind += u64::from(wrong.within(p, tol));
        }
    }
    m
}

/// Segments of `kind` in `g`.
pub fn kind_segments(g: &LineGraph, kind: LineKind) -> Vec<(DVec3, DVec3)> {
    g.edges
        .iter()
        .filter(|e| e.2 == kind)
        .map(|e| (g.vertices[e.0 as usize], g.vertices[e.1 as usize]))
        .collect()
}

/// Segments bucketed into cubic cells of side `tol` by their bounds grown
/// by `tol`, so a point's own cell lists every segment within `tol`.
struct SegmentGrid<'a> {
    segs: &'a [(DVec3, DVec3)],
    cell: f64,
    cells: HashMap<[i64; 3], Vec<u32>>,
}

impl<'a> SegmentGrid<'a> {
    fn new(segs: &'a [(DVec3, DVec3)], cell: f64) -> Self {
        let mut cells: HashMap<[i64; 3], Vec<u32>> = HashMap::new();
        let key = |p: DVec3| [p.x, p.y, p.z].map(|c| (c / cell).floor() as i64);
        for (i, &(a, b)) in segs.iter().enumerate() {
            let lo = key(a.min(b) - DVec3::splat(cell));
            let hi = key(a.max(b) + DVec3::splat(cell));
            for x in lo[0]..=hi[0] {
                for y in lo[1]..=hi[1] {
                    for z in lo[2]..=hi[2] {
                        cells.entry([x, y, z]).or_default().push(i as u32);
                    }
                }
            }
        }
        SegmentGrid { segs, cell, cells }
    }

    /// Distance from `p` to the nearest segment if it is within the
    /// grid's cell, else `None`.
    fn nearest(&self, p: DVec3) -> Option<f64> {
        let key = [p.x, p.y, p.z].map(|c| (c / self.cell).floor() as i64);
        let list = self.cells.get(&key)?;
        list.iter()
            .map(|&i| {
                let (a, b) = self.segs[i as usize];
                segment_distance(p, a, b)
            })
            .filter(|d| *d <= self.cell)
            .min_by(f64::total_cmp)
    }

    fn within(&self, p: DVec3, tol: f64) -> bool {
        let key = [p.x, p.y, p.z].map(|c| (c / self.cell).floor() as i64);
        self.cells.get(&key).is_some_and(|list| {
            list.iter().any(|&i| {
                let (a, b) = self.segs[i as usize];
                segment_distance(p, a, b) <= tol
            })
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_shifted_copy_scores_by_its_offset() {
        let truth = vec![TrueSegment {
            kind: LineKind::Ridge,
            a: DVec3::ZERO,
            b: DVec3::new(10.0, 0.0, 0.0),
        }];
        // Half the length found, 0.5 off; plus 2 of false length.
        let g = LineGraph {
            vertices: vec![
                DVec3::new(0.0, 0.5, 0.0),
                DVec3::new(5.0, 0.5, 0.0),
                DVec3::new(0.0, 3.0, 0.0),
                DVec3::new(2.0, 3.0, 0.0),
            ],
            edges: vec![(0, 1, LineKind::Ridge), (2, 3, LineKind::Ridge)],
            corners: vec![false; 4],
        };
        let [r, v] = score(&g, &truth, 1.0, 0.25);
        // Covered: x up to 5 + sqrt(1 - 0.5^2); samples every 0.25.
        assert!(
            (r.recall.unwrap() - (5.0 + 0.75f64.sqrt()) / 10.0).abs() < 0.02,
            "{r:?}"
        );
        assert!((r.precision.unwrap() - 5.0 / 7.0).abs() < 1e-9, "{r:?}");
        assert_eq!((v.recall, v.precision), (None, None));
    }
}
