//! The one seam problem the endpoint repair does not solve: a line that runs
//! along a face of the growth lattice has its smoothed points split between
//! the two cells on either side, and each cell grows its own copy of the
//! line, a few sp apart (measured on a box with a notch whose valleys lie
//! in a lattice plane: the valleys' length came out twice the truth).
//!
//! After all tiles, in the cells' canonical order, every vertex of a
//! polyline that lies within `rho` of a segment of an earlier polyline of
//! the same kind from another cell is dropped, splitting its polyline;
//! pieces of one vertex go. Within a cell, growth consumes its points and
//! never runs a line twice, so only lines from different cells are
//! compared. The result does not depend on the tiling (cells do not).

use crate::geom::LineKind;
use crate::spatial::BallGrid;
use glam::DVec3;

/// A polyline with its growth cell.
#[derive(Clone, Debug, PartialEq)]
pub struct CellPolyline {
    pub cell: [i64; 3],
    pub kind: LineKind,
    pub points: Vec<DVec3>,
}

/// Drops the copies described in the module doc from `lines` (in
/// canonical order); returns the pieces left, in order. Takes the lines
/// by value: their vertices are moved into one array as they are read,
/// so every line of a run is held once, not twice (this join is the
/// peak of a `features` run on a large scan).
pub fn drop_copies(lines: Vec<CellPolyline>, rho: f64) -> Vec<CellPolyline> {
    // Segments within rho of a vertex have an end within rho + their
    // length of it; lines' segments are at most a few gamma long.
    let longest = lines
        .iter()
        .flat_map(|l| l.points.windows(2).map(|w| w[0].distance(w[1])))
        .fold(0.0f64, f64::max);
    let reach = rho + longest;
    let total = lines.iter().map(|l| l.points.len()).sum();
    let mut pos = Vec::with_capacity(total);
    let mut heads = Vec::with_capacity(lines.len());
    for line in lines {
        heads.push(LineHead {
            cell: line.cell,
            kind: line.kind,
            first: pos.len(),
        });
        pos.extend(line.points);
    }
    let span = |l: usize| heads[l].first..heads.get(l + 1).map_or(pos.len(), |h| h.first);
    let Some(grid) = BallGrid::indexed(&pos, reach) else {
        return (0..heads.len())
            .map(|l| heads[l].polyline(pos[span(l)].to_vec()))
            .collect();
    };
    let owner = |v: usize| heads.partition_point(|h| h.first <= v) - 1;
    let mut kept = vec![true; pos.len()];
    let mut found = Vec::new();
    for l in 0..heads.len() {
        let line = &heads[l];
        for v in span(l) {
            grid.within(pos[v], reach, None, &mut found);
            let copy = found.iter().any(|n| {
                let u = n.index as usize;
                let other = owner(u);
                other < l
                    && heads[other].cell != line.cell
                    && heads[other].kind == line.kind
                    && near_kept_segment(
                        &pos[span(other)],
                        u - heads[other].first,
                        u,
                        &kept,
                        pos[v],
                        rho,
                    )
            });
            if copy {
                kept[v] = false;
            }
        }
    }
    drop(grid);
    let mut out = Vec::new();
    for (l, head) in heads.iter().enumerate() {
        let mut piece: Vec<DVec3> = Vec::new();
        for v in span(l) {
            if kept[v] {
                piece.push(pos[v]);
            } else if !piece.is_empty() {
                push_piece(&mut out, head, std::mem::take(&mut piece));
            }
        }
        push_piece(&mut out, head, piece);
    }
    out
}

/// A line's cell, kind and first vertex in the join's vertex array.
struct LineHead {
    cell: [i64; 3],
    kind: LineKind,
    first: usize,
}

impl LineHead {
    fn polyline(&self, points: Vec<DVec3>) -> CellPolyline {
        CellPolyline {
            cell: self.cell,
            kind: self.kind,
            points,
        }
    }
}

fn push_piece(out: &mut Vec<CellPolyline>, line: &LineHead, piece: Vec<DVec3>) {
    if piece.len() >= 2 {
        out.push(line.polyline(piece));
    }
}

/// Whether `p` lies within `rho` of a segment of `points` at vertex `k`
/// (global vertex index `v`) whose ends are both kept.
fn near_kept_segment(
    points: &[DVec3],
    k: usize,
    v: usize,
    kept: &[bool],
    p: DVec3,
    rho: f64,
) -> bool {
    let mut near = false;
    if k > 0 && kept[v] && kept[v - 1] {
        near |= segment_distance(p, points[k - 1], points[k]) <= rho;
    }
    if k + 1 < points.len() && kept[v] && kept[v + 1] {
        near |= segment_distance(p, points[k], points[k + 1]) <= rho;
    }
    near
}

/// Distance from `p` to the segment `a b`.
pub fn segment_distance(p: DVec3, a: DVec3, b: DVec3) -> f64 {
    let ab = b - a;
    let len2 = ab.length_squared();
    let t = if len2 > 0.0 {
        ((p - a).dot(ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (a + ab * t).distance(p)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn line(cell: i64, y: f64, from: f64, to: f64) -> CellPolyline {
        CellPolyline {
            cell: [cell, 0, 0],
            kind: LineKind::Valley,
            points: (0..=10)
                .map(|i| DVec3::new(from + (to - from) * i as f64 / 10.0, y, 0.0))
                .collect(),
        }
    }

    #[test]
    fn a_copy_from_the_next_cell_goes_but_its_overhang_stays() {
        let a = line(0, 0.0, 0.0, 1.0);
        // A copy 0.02 off over [0.5, 1.5]: the part over [0.5, 1] goes.
        let b = line(1, 0.02, 0.5, 1.5);
        let out = drop_copies(vec![a.clone(), b], 0.05);
        assert_eq!(out.len(), 2);
        assert_eq!(out[0], a);
        let xs: Vec<f64> = out[1].points.iter().map(|p| p.x).collect();
        assert!(xs[0] > 1.0 && xs.len() == 5, "{xs:?}");
        // Same cell, or far enough: nothing goes.
        let c = line(0, 0.02, 0.5, 1.5);
        assert_eq!(drop_copies(vec![a.clone(), c.clone()], 0.05).len(), 2);
        let d = line(1, 0.2, 0.0, 1.0);
        assert_eq!(drop_copies(vec![a.clone(), d.clone()], 0.05), vec![a, d]);
    }
}
