//! Repair and smoothing of the grown polylines (paper 5 section 5, last
//! part), over all polylines at once after every tile: this is also how
//! polylines cut by the growth cells (and so by tiles) join up.
//!
//! - Repair: each endpoint has a connection cone (apex the endpoint, axis
//!   its end tangent, length `alpha gamma_max`, half-angle `mu`). The
//!   nearest vertex of another line of its kind inside the cone takes it:
//!   another line's endpoint whose tangent opposes (`T_p . T_q < 0`): the
//!   lines join; an interior vertex: joined to it, which becomes a corner.
//!   The end tangent is the last segment's direction (the paper allows
//!   that or a cubic through the last four vertices). Deviation: the
//!   enhancement's corners are targets too, so lines reach the corner they
//!   run into instead of stopping short of it; and before the cone rule,
//!   two ends meeting at an angle are extended to where their rays meet
//!   (`corner_meetings`).
//! - Relaxation: 1-2 passes over each chain of degree-2 vertices, ends and
//!   corners fixed, moving each vertex onto the perpendicular bisector of
//!   its neighbours in their plane, keeping the triangle's area (Fig. 10).
//!
//! Endpoints are visited in the polylines' canonical order (cell, then
//! growth order), never in tile order, so the result does not depend on
//! the tiling.

use super::lines::LineGraph;
use crate::geom::LineKind;
use crate::spatial::BallGrid;
use glam::DVec3;

/// The connection cone.
#[derive(Clone, Copy, Debug)]
pub struct Cone {
    pub length: f64,
    pub half_angle: f64,
}

/// Who a vertex of the graph belongs to.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Owner {
    Line(u32),
    Corner,
}

/// Joins `polylines` (each `(kind, vertices)`, in canonical order) and the
/// `corners` into one graph by the cone rule. Takes the polylines by
/// value: their vertices move into the graph one line at a time, so the
/// join holds each vertex once (it is the peak of a large `features` run).
pub fn repair(
    polylines: Vec<(LineKind, Vec<DVec3>)>,
    corners: &[(LineKind, DVec3)],
    cone: Cone,
    reach: f64,
) -> LineGraph {
    let mut g = LineGraph::default();
    let total: usize = polylines.iter().map(|(_, p)| p.len()).sum::<usize>() + corners.len();
    g.vertices.reserve_exact(total);
    let mut owner = Vec::with_capacity(total);
    let mut kinds = Vec::with_capacity(total);
    // (vertex, unit outward end direction, polyline).
    let mut ends = Vec::new();
    for (k, (kind, pts)) in polylines.into_iter().enumerate() {
        let first = g.vertices.len() as u32;
        if pts.len() >= 2 {
            let last = first + pts.len() as u32 - 1;
            let span = TANGENT_SPAN * reach;
            ends.push((first, end_direction(pts.iter(), span), k as u32));
            ends.push((last, end_direction(pts.iter().rev(), span), k as u32));
        }
        for i in 0..pts.len() as u32 {
            owner.push(Owner::Line(k as u32));
            kinds.push(kind);
            if i > 0 {
                g.edges.push((first + i - 1, first + i, kind));
            }
        }
        g.vertices.extend(pts);
    }
    for (kind, c) in corners {
        g.vertices.push(*c);
        owner.push(Owner::Corner);
        kinds.push(*kind);
    }
    // Per vertex: its index in `ends`, or NOT_END.
    let mut end_at = vec![NOT_END; g.vertices.len()];
    for (e, &(v, _, _)) in ends.iter().enumerate() {
        end_at[v as usize] = e as u32;
    }
    let tangent = |end_at: &[u32], v: usize| match end_at[v] {
        NOT_END => DVec3::ZERO,
        e => ends[e as usize].1,
    };
    let mut joined = vec![false; g.vertices.len()];
    let mut corner = vec![false; g.vertices.len()];
    let meets = corner_meetings(&g.vertices, &ends, &kinds, cone, reach);
    for (a, b, m) in meets {
        let v = g.vertices.len() as u32;
        g.vertices.push(m);
        owner.push(Owner::Corner);
        kinds.push(kinds[a as usize]);
        end_at.push(NOT_END);
        joined.push(false);
        corner.push(true);
        joined[a as usize] = true;
        joined[b as usize] = true;
        let k = kinds[a as usize];
        g.edges.push((a, v, k));
        g.edges.push((b, v, k));
    }
    let Some(grid) = BallGrid::indexed(&g.vertices, cone.length) else {
        return g;
    };
    let cos = cone.half_angle.cos();
    let mut found = Vec::new();
    let mut added = Vec::new();
    for &(a, _, line) in &ends {
        let (a, t) = (a as usize, tangent(&end_at, a as usize));
        if joined[a] || t == DVec3::ZERO {
            continue;
        }
        grid.nearest_first(g.vertices[a], cone.length, Some(a as u32), &mut found);
        for n in &found {
            let q = n.index as usize;
            if kinds[q] != kinds[a] || owner[q] == Owner::Line(line) {
                continue;
            }
            let d = g.vertices[q] - g.vertices[a];
            if d.dot(t) < cos * d.length() {
                continue;
            }
            let target = match owner[q] {
                Owner::Corner => true,
                Owner::Line(_) if end_at[q] != NOT_END => {
                    !joined[q] && tangent(&end_at, q).dot(t) < 0.0
                }
                Owner::Line(_) => {
                    corner[q] = true;
                    true
                }
            };
            if target {
                added.push((a as u32, q as u32, kinds[a]));
                joined[a] = true;
                if end_at[q] != NOT_END {
                    joined[q] = true;
                }
                if owner[q] == Owner::Corner {
                    corner[q] = true;
                }
                break;
            }
        }
    }
    g.edges.extend(added);
    g.corners = corner;
    g.drop_isolated();
    g
}

/// Lines meeting at an angle (their end tangents at least
/// [`MEET_ANGLE`] apart) stop short of the corner, where the enhancement
/// sees two or three faces (the stepped block at noise 0.1 sp: ridges
/// ended 3-4 sp short of the box corners, 4 % of their length). The cone
/// rule cannot close that gap: the other line's end is off to the side,
/// and the paper only joins ends whose tangents oppose. Deviation, named:
/// two ends of one kind, of different lines, whose rays pass within
/// `reach` of each other at most a cone's length ahead of both (and at
/// most `reach / 2` behind) meet at the midpoint of their closest
/// approach, a new corner (a third line then reaches it by the cone
/// rule). Each end takes the meeting nearest ahead; ends in the
/// polylines' canonical order, so no tiling changes the result.
fn corner_meetings(
    vertices: &[DVec3],
    ends: &[(u32, DVec3, u32)],
    kinds: &[LineKind],
    cone: Cone,
    reach: f64,
) -> Vec<(u32, u32, DVec3)> {
    let end_pos: Vec<DVec3> = ends.iter().map(|e| vertices[e.0 as usize]).collect();
    let span = 2.0 * cone.length + reach;
    let Some(grid) = BallGrid::indexed(&end_pos, span) else {
        return Vec::new();
    };
    let parallel = MEET_ANGLE.cos();
    let mut taken = vec![false; ends.len()];
    let mut found = Vec::new();
    let mut out = Vec::new();
    for (ea, &(a, ta, la)) in ends.iter().enumerate() {
        let pa = vertices[a as usize];
        if taken[ea] || ta == DVec3::ZERO {
            continue;
        }
        grid.within(pa, span, Some(ea as u32), &mut found);
        let mut best: Option<(f64, usize, DVec3)> = None;
        for n in &found {
            let eb = n.index as usize;
            let (b, tb, lb) = ends[eb];
            let pb = vertices[b as usize];
            if taken[eb] || lb == la || kinds[b as usize] != kinds[a as usize] {
                continue;
            }
            let c = ta.dot(tb);
            if tb == DVec3::ZERO || c.abs() > parallel {
                continue;
            }
            // Closest approach of pa + s ta and pb + u tb.
            let w = pa - pb;
            let (d, e) = (ta.dot(w), tb.dot(w));
            let den = 1.0 - c * c;
            let (s, u) = ((c * e - d) / den, (e - c * d) / den);
            let (qa, qb) = (pa + ta * s, pb + tb * u);
            let ok = |t: f64| t >= -0.5 * reach && t <= cone.length;
            if !(ok(s) && ok(u)) || qa.distance(qb) > reach {
                continue;
            }
            let key = s.max(u);
            if best.is_none_or(|(k, i, _)| key < k || (key == k && eb < i)) {
                best = Some((key, eb, (qa + qb) * 0.5));
            }
        }
        if let Some((_, eb, m)) = best {
            taken[ea] = true;
            taken[eb] = true;
            out.push((a, ends[eb].0, m));
        }
    }
    out
}

/// `end_at` of a vertex that ends no polyline.
const NOT_END: u32 = u32::MAX;

/// How far back along a line its end tangent looks, in growth radii: the
/// last segment alone turns with the sideways scatter of the last growth
/// point (lines 3 d apart on one crest, their last segments hooked, were
/// left unjoined: a corrugated sheet at noise 0.5 sp).
const TANGENT_SPAN: f64 = 2.0;

/// The unit direction out of a line's end (`pts` from that end): from the
/// first vertex at least `span` back (or the line's far end) to the end;
/// the paper's "tangent at the end" (the last segment, or a cubic through
/// the last four vertices) over a span of a few growth steps.
fn end_direction<'a>(mut pts: impl Iterator<Item = &'a DVec3> + Clone, span: f64) -> DVec3 {
    let Some(&end) = pts.next() else {
        return DVec3::ZERO;
    };
    let mut back = end;
    for &p in pts {
        back = p;
        if p.distance(end) >= span {
            break;
        }
    }
    (end - back).normalize_or_zero()
}

/// Smallest angle between two end tangents that `corner_meetings` takes
/// for a corner (below it, the lines continue each other: the cone rule).
pub const MEET_ANGLE: f64 = 20.0 * std::f64::consts::PI / 180.0;

#[cfg(test)]
mod tests {
    use super::*;

    /// The end direction looks past a hooked last segment.
    #[test]
    fn end_direction_spans_more_than_the_last_segment() {
        let pts = [
            DVec3::new(0.0, 0.3, 0.0),
            DVec3::new(0.2, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(2.0, 0.0, 0.0),
            DVec3::new(3.0, 0.0, 0.0),
        ];
        let d = end_direction(pts.iter(), 2.0);
        assert!(d.x < -0.98, "{d}");
        let last = end_direction(pts.iter(), 0.1);
        assert!(last.y > 0.8, "{last}");
        assert_eq!(end_direction([].iter(), 1.0), DVec3::ZERO);
    }

    /// Three ridges along the axes, each stopping `short` before the
    /// origin, as at a box corner.
    fn corner_lines(short: f64) -> Vec<(LineKind, Vec<DVec3>)> {
        [DVec3::X, DVec3::Y, DVec3::Z]
            .map(|a| {
                let pts = (0..8).map(|i| a * (short + 0.5 * i as f64)).collect();
                (LineKind::Ridge, pts)
            })
            .to_vec()
    }

    #[test]
    fn lines_stopping_short_of_a_corner_meet_there() {
        let cone = Cone {
            length: 3.0,
            half_angle: std::f64::consts::PI / 6.0,
        };
        let g = repair(corner_lines(1.5), &[], cone, 1.0);
        assert_eq!(g.components(), 1, "{g:?}");
        // The three lines end at one corner vertex at the origin.
        let at: Vec<usize> = (0..g.vertices.len()).filter(|&v| g.corners[v]).collect();
        assert_eq!(at.len(), 1, "{at:?}");
        assert!(g.vertices[at[0]].length() < 1e-9, "{}", g.vertices[at[0]]);
        // Nothing is joined beyond the cone.
        let far = repair(corner_lines(3.5), &[], cone, 1.0);
        assert_eq!(far.components(), 3);
    }

    #[test]
    fn ends_continuing_each_other_join_by_the_cone_not_at_a_corner() {
        let cone = Cone {
            length: 3.0,
            half_angle: std::f64::consts::PI / 6.0,
        };
        let a: Vec<DVec3> = (0..5).map(|i| DVec3::X * f64::from(i)).collect();
        let b: Vec<DVec3> = (0..5).map(|i| DVec3::X * (6.0 + f64::from(i))).collect();
        let g = repair(
            vec![(LineKind::Ridge, a), (LineKind::Ridge, b)],
            &[],
            cone,
            1.0,
        );
        assert_eq!(g.components(), 1);
        assert_eq!(g.corner_count(), 0);
        assert_eq!(g.vertices.len(), 10);
    }
}
