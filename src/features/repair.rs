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
//!   run into instead of stopping short of it.
//! - Relaxation: 1-2 passes over each chain of degree-2 vertices, ends and
//!   corners fixed, moving each vertex onto the perpendicular bisector of
//!   its neighbours in their plane, keeping the triangle's area (Fig. 10).
//!
//! Endpoints are visited in the polylines' canonical order (cell, then
//! growth order), never in tile order, so the result does not depend on
//! the tiling.

use super::grid::BallGrid;
use super::lines::LineGraph;
use crate::synth::LineKind;
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
/// `corners` into one graph by the cone rule.
pub fn repair(
    polylines: &[(LineKind, Vec<DVec3>)],
    corners: &[(LineKind, DVec3)],
    cone: Cone,
) -> LineGraph {
    let mut g = LineGraph::default();
    let mut owner = Vec::new();
    let mut kinds = Vec::new();
    // (vertex, outward end direction, polyline).
    let mut ends = Vec::new();
    for (k, (kind, pts)) in polylines.iter().enumerate() {
        let first = g.vertices.len() as u32;
        for (i, p) in pts.iter().enumerate() {
            g.vertices.push(*p);
            owner.push(Owner::Line(k as u32));
            kinds.push(*kind);
            if i > 0 {
                g.edges
                    .push((first + i as u32 - 1, first + i as u32, *kind));
            }
        }
        if pts.len() >= 2 {
            let last = first + pts.len() as u32 - 1;
            ends.push((first, pts[0] - pts[1], k as u32));
            ends.push((last, pts[pts.len() - 1] - pts[pts.len() - 2], k as u32));
        }
    }
    for (kind, c) in corners {
        g.vertices.push(*c);
        owner.push(Owner::Corner);
        kinds.push(*kind);
    }
    let mut tangent = vec![DVec3::ZERO; g.vertices.len()];
    let mut is_end = vec![false; g.vertices.len()];
    for &(v, t, _) in &ends {
        tangent[v as usize] = t.normalize_or_zero();
        is_end[v as usize] = true;
    }
    let ids: Vec<u64> = (0..g.vertices.len() as u64).collect();
    let Some(grid) = BallGrid::new(&g.vertices, &ids, cone.length) else {
        return g;
    };
    let cos = cone.half_angle.cos();
    let mut joined = vec![false; g.vertices.len()];
    let mut corner = vec![false; g.vertices.len()];
    let mut found = Vec::new();
    let mut added = Vec::new();
    for &(a, _, line) in &ends {
        let (a, t) = (a as usize, tangent[a as usize]);
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
                Owner::Line(_) if is_end[q] => !joined[q] && tangent[q].dot(t) < 0.0,
                Owner::Line(_) => {
                    corner[q] = true;
                    true
                }
            };
            if target {
                added.push((a as u32, q as u32, kinds[a]));
                joined[a] = true;
                if is_end[q] {
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
