//! The per-point stages of the feature kernel over one tile's loaded
//! points, each a pure function of the previous stage's values (paper 5
//! sections 2-4): classification, enhancement, corner merging, smoothing.
//! Which points each stage runs for, and why their values are exact, is
//! `kernel.rs`'s business; here each stage computes what it is asked for.

use super::curvature::{oriented_normal, point_quadric};
use super::enhance::{enhance, EnhanceParams};
use super::hood::{HoodIndex, HoodScratch};
use super::lift::two_sided_lift;
use super::params::Resolved;
use super::smooth::{smooth_point, SmoothParams, Smoothed};
use crate::geom::LineKind;
use crate::pipeline::KernelError;
use crate::spatial::BallGrid;
use crate::tiling::TilePoints;
use glam::{DVec2, DVec3};
use rayon::prelude::*;

/// Section 2's classification of a point: its kind and weight `|k_i|`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Class {
    pub kind: LineKind,
    pub weight: f64,
}

/// `k_i` (the principal curvature of larger magnitude) against `alpha`:
/// valley if `k_i < -alpha`, ridge if `k_i > alpha`; nothing for a point
/// whose curvature is flagged.
pub fn classify(k1: f32, k2: f32, flags: u8, alpha: f64) -> Option<Class> {
    if flags != 0 || !(k1.is_finite() && k2.is_finite()) {
        return None;
    }
    let k = f64::from(if k1.abs() >= k2.abs() { k1 } else { k2 });
    let kind = if k > alpha {
        LineKind::Ridge
    } else if k < -alpha {
        LineKind::Valley
    } else {
        return None;
    };
    Some(Class {
        kind,
        weight: k.abs(),
    })
}

/// How elongated a curve-fitting set must be (`(l0 - l1) / (l0 + l1)`,
/// see [`EnhanceParams::elongation`]). Lower than the smoothing's 0.6: a
/// band of feature points as wide as a third of the local set's diameter
/// (creases and rounded crests at r = 3 d) reaches only about 0.5, and at
/// 0.6 half the sets failed (wavy sheet, noise 0.1 sp: recall 88 % at 0.6,
/// 93 % at 0.4).
pub const CURVE_ELONGATION: f64 = 0.4;

/// Section 3's outcome for one feature point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Enh {
    pub edge: DVec3,
    /// Corner position and weight `1 / |c - e|`.
    pub corner: Option<(DVec3, f64)>,
}

/// Per-kind indexes over the tile's feature points.
pub struct FeatureSets<'a> {
    /// Loaded-point indices of each kind's feature points.
    pub members: &'a [Vec<u32>; 2],
    /// Fixed-radius grids over their positions (cell `phi`).
    pub grids: [Option<BallGrid<'a>>; 2],
}

pub fn kind_slot(kind: LineKind) -> usize {
    match kind {
        LineKind::Ridge => 0,
        LineKind::Valley => 1,
    }
}

/// Each kind's feature points (ridge, valley): loaded indices, positions,
/// ids.
#[derive(Default)]
pub struct FeatureLists {
    pub members: [Vec<u32>; 2],
    pub positions: [Vec<DVec3>; 2],
    pub ids: [Vec<u64>; 2],
}

/// Each kind's feature points of the tile.
pub fn feature_sets(tile: &TilePoints, class: &[Option<Class>]) -> FeatureLists {
    let mut f = FeatureLists::default();
    for (i, c) in class.iter().enumerate() {
        if let Some(c) = c {
            let k = kind_slot(c.kind);
            f.members[k].push(i as u32);
            f.positions[k].push(tile.points[i]);
            f.ids[k].push(tile.ids[i]);
        }
    }
    f
}

/// Enhances the feature points `which` (loaded indices); returns each one's
/// outcome and the largest shortfall of the loaded region around them.
pub(crate) fn enhance_points(
    tile: &TilePoints,
    hood: &HoodIndex,
    class: &[Option<Class>],
    sets: &FeatureSets,
    which: &[u32],
    p: &Resolved,
) -> Result<(Vec<Option<Enh>>, f64), KernelError> {
    let ep = EnhanceParams {
        radius: p.growth_radius,
        sector: p.sector,
        min_points: p.min_curve_points,
        elongation: CURVE_ELONGATION,
    };
    let out: Vec<(Option<Enh>, f64)> = which
        .par_iter()
        .map_init(
            || {
                (
                    HoodScratch::default(),
                    Vec::new(),
                    Vec::new(),
                    Vec::new(),
                    Vec::new(),
                )
            },
            |(hs, buf, found, q, w), &i| -> Result<(Option<Enh>, f64), KernelError> {
                let i = i as usize;
                let reach = hood.query(tile, i, hs)?.max(p.phi);
                let short = reach - tile.room(tile.points[i]);
                let Some(c) = class[i] else {
                    return Ok((None, short));
                };
                let toward = oriented_normal(tile, i);
                let Ok(quad) = point_quadric(&tile.points, i, &hs.nbrs, toward, buf) else {
                    return Ok((None, short));
                };
                let k = kind_slot(c.kind);
                let Some(grid) = &sets.grids[k] else {
                    return Ok((None, short));
                };
                let pi = tile.points[i];
                grid.within(pi, p.phi, None, found);
                q.clear();
                w.clear();
                for n in found.iter() {
                    let j = sets.members[k][n.index as usize] as usize;
                    let l = quad.frame.local(tile.points[j]);
                    q.push(DVec2::new(l.x, l.y));
                    w.push(class[j].map_or(0.0, |c| c.weight));
                }
                let at = quad.frame.local(pi);
                let Some(e) = enhance(q, w, DVec2::new(at.x, at.y), &ep) else {
                    return Ok((None, short));
                };
                // The crease is looked for among the points around the
                // edge point, not around p_i (whose neighbourhood may hold
                // a mere sliver of the far face).
                let rough = quad.lift(e.edge.x, e.edge.y);
                let reach_edge = hood.around(rough, hs) + rough.distance(pi);
                let short = short.max(reach_edge - tile.room(pi));
                buf.clear();
                buf.extend(hs.nbrs.iter().map(|n| tile.points[n.index as usize]));
                let edge = two_sided_lift(&quad, buf, e.edge, e.tangent, p.growth_radius);
                if edge.distance(pi) > p.phi {
                    return Ok((None, short));
                }
                let corner = e
                    .corner
                    .map(|c| quad.lift(c.x, c.y))
                    .filter(|c| c.distance(pi) <= p.phi)
                    .map(|c| (c, 1.0 / c.distance(edge).max(f64::MIN_POSITIVE)));
                Ok((Some(Enh { edge, corner }), short))
            },
        )
        .collect::<Result<_, _>>()?;
    let short = out.iter().map(|o| o.1).fold(f64::NEG_INFINITY, f64::max);
    Ok((out.into_iter().map(|o| o.0).collect(), short))
}

/// A candidate corner of section 3, before merging.
#[derive(Clone, Copy, Debug)]
pub struct CornerCand {
    pub at: DVec3,
    pub weight: f64,
    pub id: u64,
}

/// Section 3's merge: among the corners within `epsilon` of corner `i`
/// (itself included), the one whose weight is nearest their mean weight
/// stays a corner; `i` is kept when that is itself. (The paper merges one
/// neighbourhood at a time; deciding each corner by its own neighbourhood
/// is the order-free reading, so every tiling agrees.)
pub fn corner_kept(i: usize, cands: &[CornerCand], grid: &BallGrid, epsilon: f64) -> bool {
    let mut found = Vec::new();
    grid.within(cands[i].at, epsilon, None, &mut found);
    let mean = found
        .iter()
        .map(|n| cands[n.index as usize].weight)
        .sum::<f64>()
        / found.len().max(1) as f64;
    let rep = found.iter().map(|n| n.index as usize).min_by(|&a, &b| {
        let (da, db) = (
            (cands[a].weight - mean).abs(),
            (cands[b].weight - mean).abs(),
        );
        da.total_cmp(&db).then(cands[a].id.cmp(&cands[b].id))
    });
    rep == Some(i)
}

/// Section 4 over the enhanced points `which` of one kind: `positions` /
/// `ids` are all the kind's enhanced points (edge points and kept corners),
/// `grid` over them, `corners` the kept corners.
pub fn smooth_points(
    which: &[u32],
    positions: &[DVec3],
    grid: &BallGrid,
    corners: &[DVec3],
    corner_grid: Option<&BallGrid>,
    p: &Resolved,
) -> Vec<Option<DVec3>> {
    let sp = SmoothParams {
        delta: p.delta,
        growth: p.delta_growth,
        delta_max: p.delta_max,
        rho: p.rho,
    };
    which
        .par_iter()
        .map_init(
            || (Vec::new(), Vec::new(), Vec::new(), Vec::new()),
            |(found, cfound, near, buf), &i| {
                let s = positions[i as usize];
                for within in [p.delta, p.delta_max] {
                    grid.within(s, within, None, found);
                    near.clear();
                    if let Some(cg) = corner_grid {
                        cg.within(s, within, None, cfound);
                        near.extend(cfound.iter().map(|n| corners[n.index as usize]));
                    }
                    match smooth_point(s, found, within, positions, near, &sp, buf) {
                        Smoothed::At(x) => return Some(x),
                        Smoothed::Noise => return None,
                        Smoothed::Wider => {}
                    }
                }
                None
            },
        )
        .collect()
}
