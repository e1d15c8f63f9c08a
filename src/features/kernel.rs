//! The feature tile kernel (paper 5 sections 2-5) and its seam policy.
//!
//! Polylines grow greedily (section 5), so growing them per tile would make
//! them depend on where tiles end. They grow instead in the cells of a
//! lattice of side `cell` anchored at the store origin, which no tiling
//! moves: a cell's polylines use the smoothed points whose *source* point
//! lies in the cell, and nothing else. A tile owns the cells whose min
//! corner lies in its core (half-open, so exactly one tile owns a cell),
//! and computes the per-point stages for every point those cells need.
//! Polylines that leave a cell (and so, possibly, a tile) are joined after
//! all tiles by the paper's own endpoint repair (`repair.rs`), run over
//! every polyline in cell order: the result is the same for any tiling.
//!
//! Exactness of the per-point stages. Every stage at a point reads only the
//! previous stage's values within a fixed distance (the stage's radius):
//! - enhancement (section 3): the quadric (the curvature neighbourhood,
//!   radius `r` or the k-th distance) and the feature points within `phi`;
//!   its edge point and corner lie within `phi` of the source point;
//! - corner status (merging within `epsilon`): the corners within
//!   `epsilon`, from sources within `2 phi + epsilon`;
//! - smoothing (section 4): the enhanced points within `delta_max`, from
//!   sources within `2 phi + delta_max` whose corner status is known; the
//!   smoothed point lies within `phi + delta_max` of its source;
//! - seed priority (section 5): the kept corners within the cap of the
//!   smoothed point, from sources within `2 phi + delta_max + cap`.
//!
//! So the points of owned cells depend on sources within
//! `chain = 2 phi + epsilon + 2 phi + delta_max + cap` of the owned region
//! (`[core.min, core.max + cell)`), each of which needs its own
//! enhancement radius loaded. Each stage runs for the points within the
//! remaining chain of the owned region; the kernel checks that the loaded
//! region covers it and asks for more margin otherwise.

use super::crest::{place_on_crests, Slab};
use super::curvature::oriented_normal;
use super::curvature::VALUES;
use super::hood::HoodIndex;
use super::params::Resolved;
use super::peak::on_crest;
use super::polyline::grow_polylines;
use super::stages::{
    classify, corner_kept, enhance_points, feature_sets, kind_slot, smooth_points, Class,
    CornerCand, Enh, FeatureLists, FeatureSets,
};
use super::{CURVATURE, CURVATURE_FLAGS};
use crate::geom::Aabb;
use crate::geom::LineKind;
use crate::pipeline::{KernelError, TileFault, TileKernel};
use crate::spatial::BallGrid;
use crate::store::{ColumnSpec, FLAGS, NORMALS};
use crate::tiling::{TilePoints, Values};
use glam::DVec3;
use rayon::prelude::*;
use std::collections::BTreeMap;

/// The kernel over a store with curvature columns ([`CURVATURE`],
/// [`CURVATURE_FLAGS`]).
pub struct FeaturesKernel {
    pub params: Resolved,
    pub margin: f64,
}

/// Points counted per kind (ridge, valley), over the points of owned cells.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FeatureCounts {
    /// Section 2's potential feature points.
    pub candidates: [u64; 2],
    /// Points the enhancement moved onto a potential line (edge points).
    pub enhanced: [u64; 2],
    /// Enhanced points the smoothing kept (not noise).
    pub smoothed: [u64; 2],
    /// Corners kept after merging.
    pub corners: [u64; 2],
}

impl FeatureCounts {
    pub fn merge(&mut self, o: &FeatureCounts) {
        for (a, b) in [
            (&mut self.candidates, o.candidates),
            (&mut self.enhanced, o.enhanced),
            (&mut self.smoothed, o.smoothed),
            (&mut self.corners, o.corners),
        ] {
            a[0] += b[0];
            a[1] += b[1];
        }
    }
}

/// The polylines of one kind grown in one cell.
#[derive(Clone, Debug, PartialEq)]
pub struct CellLines {
    pub key: [i64; 3],
    pub kind: LineKind,
    pub lines: Vec<Vec<DVec3>>,
}

/// One tile's contribution: its owned cells' polylines (sorted by cell and
/// kind), kept corners (by source id), counts.
#[derive(Clone, Debug, Default)]
pub struct FeaturesTile {
    pub cells: Vec<CellLines>,
    pub corners: Vec<(u64, LineKind, DVec3)>,
    pub counts: FeatureCounts,
}

impl TileKernel for FeaturesKernel {
    type Output = FeaturesTile;

    fn name(&self) -> &'static str {
        "features: lines"
    }

    fn margin(&self) -> f64 {
        self.margin
    }

    fn reads(&self) -> &[ColumnSpec] {
        // The stages orient their frames by the normals, as curvature did.
        &[NORMALS, FLAGS, CURVATURE, CURVATURE_FLAGS]
    }

    fn run(&self, tile: &TilePoints) -> Result<FeaturesTile, KernelError> {
        let p = &self.params;
        let own = Aabb::new(tile.core.min, tile.core.max + DVec3::splat(p.cell));
        let dist = |i: usize| gap(&own, tile.points[i]);
        let chain = p.chain();
        // Enhancement reads the classes of feature points within `phi` of
        // the points it runs for; each class reads the crest test's ball.
        let class = self.classes(tile, &own, chain + p.phi)?;
        let classed = chain + p.phi + p.peak.map_or(0.0, |t| t.wide);
        let which: Vec<u32> = (0..tile.points.len())
            .filter(|&i| class[i].is_some() && dist(i) <= chain)
            .map(|i| i as u32)
            .collect();
        let FeatureLists {
            members,
            positions,
            ids,
        } = feature_sets(tile, &class);
        let sets = FeatureSets {
            members: &members,
            grids: [0, 1].map(|k| BallGrid::new(&positions[k], &ids[k], p.phi)),
        };
        let hood = HoodIndex::build(tile, p.hood)?;
        let (enh, short) = enhance_points(tile, &hood, &class, &sets, &which, p)?;
        KernelError::unless_short(short.max(uncovered(tile, &own, classed)), tile.margin)?;
        let status = corner_status(tile, &which, &enh, &class, &dist, p);
        let mut out = FeaturesTile::default();
        // The crest's slabs query the tile's points: the curvature
        // neighbourhood's grid when it has one (no second index).
        let own_grid = match (hood.radius_grid(), p.crest) {
            (None, Some(slab)) => BallGrid::new(&tile.points, &tile.ids, slab.reach()),
            _ => None,
        };
        let crest_grid = hood.radius_grid().or(own_grid.as_ref());
        let owned = |i: usize| owns(tile, tile.points[i], p.cell);
        for kind in [LineKind::Ridge, LineKind::Valley] {
            let entries = Entries::collect(tile, &which, &enh, &class, &status, kind);
            let smoothed = entries.smooth(&dist, p);
            let corners = &entries.corners;
            let cgrid = BallGrid::new(&corners.pos, &corners.ids, p.corner_cap());
            // Priorities in parallel (a query each), grouped in entry order.
            let prios: Vec<Option<(DVec3, f64)>> = smoothed
                .par_iter()
                .enumerate()
                .map_init(Vec::new, |found, (e, s)| {
                    let src = entries.source[e] as usize;
                    match (s, owned(src)) {
                        (Some(s), true) => {
                            Some((*s, priority(*s, cgrid.as_ref(), p.corner_cap(), found)))
                        }
                        _ => None,
                    }
                })
                .collect();
            let mut groups: BTreeMap<[i64; 3], CellPoints> = BTreeMap::new();
            for (e, sp) in prios.into_iter().enumerate() {
                if let Some((s, prio)) = sp {
                    let key = cell_key(tile.points[entries.source[e] as usize], p.cell);
                    groups
                        .entry(key)
                        .or_default()
                        .push((s, entries.ids[e], prio));
                }
            }
            let mut cells = grow_cells(groups, kind, p);
            if let Some(slab) = p.crest {
                if let Some(grid) = crest_grid {
                    let short = crests(&mut cells, kind, grid, tile, slab)?;
                    KernelError::unless_short(short, tile.margin)?;
                }
            }
            out.cells.extend(cells);
            entries.count(kind, &smoothed, &owned, &mut out.counts);
            for (c, &src) in corners.source.iter().enumerate() {
                if owned(src as usize) {
                    out.corners
                        .push((tile.ids[src as usize], kind, corners.pos[c]));
                }
            }
        }
        for (i, c) in class.iter().enumerate() {
            if let (Some(c), true) = (c, owned(i)) {
                out.counts.candidates[kind_slot(c.kind)] += 1;
            }
        }
        out.cells.sort_by_key(|c| (c.key, c.kind));
        out.corners.sort_by_key(|c| (c.0, c.1));
        Ok(out)
    }
}

impl FeaturesKernel {
    /// Section 2's class of every loaded point, from the curvature columns,
    /// kept only on the crest of its curvature (`peak.rs`) for the points
    /// within `reach` of the owned region (no other class is read).
    fn classes(
        &self,
        tile: &TilePoints,
        own: &Aabb,
        reach: f64,
    ) -> Result<Vec<Option<Class>>, KernelError> {
        let k_of = curvature_of(tile)?;
        let alpha = self.params.alpha;
        let mut class: Vec<Option<Class>> = (0..tile.points.len())
            .map(|i| k_of.classify(i, alpha))
            .collect();
        let Some(test) = self.params.peak else {
            return Ok(class);
        };
        let Some(grid) = BallGrid::new(&tile.points, &tile.ids, test.wide) else {
            return Err(KernelError::Failed(TileFault::CrestRadius {
                radius: test.wide,
                points: tile.points.len(),
            }));
        };
        // NaN where unknown: 8 B a loaded point, not an Option's 16.
        let k_i: Vec<f64> = (0..tile.points.len())
            .map(|j| k_of.k_i(j).unwrap_or(f64::NAN))
            .collect();
        class
            .par_iter_mut()
            .enumerate()
            .for_each_init(Vec::new, |found, (i, c)| {
                let Some(kind) = c.map(|c| c.kind) else {
                    return;
                };
                let keep = gap(own, tile.points[i]) <= reach
                    && oriented_normal(tile, i).is_some_and(|n| {
                        let sign = if kind == LineKind::Ridge { 1.0 } else { -1.0 };
                        let value = |j: usize| Some(sign * k_i[j]).filter(|k| k.is_finite());
                        on_crest(tile.points[i], n, &grid, &value, &test, found)
                    });
                if !keep {
                    *c = None;
                }
            });
        Ok(class)
    }
}

/// A tile's curvature columns.
struct CurvatureColumns<'a> {
    vals: &'a [f32],
    flags: &'a [u8],
}

fn curvature_of(tile: &TilePoints) -> Result<CurvatureColumns<'_>, KernelError> {
    match (tile.column(&CURVATURE), tile.column(&CURVATURE_FLAGS)) {
        (Some(Values::F32(vals)), Some(Values::U8(flags))) => Ok(CurvatureColumns { vals, flags }),
        _ => Err(KernelError::Failed(TileFault::NoCurvature)),
    }
}

impl CurvatureColumns<'_> {
    fn classify(&self, j: usize, alpha: f64) -> Option<Class> {
        let v = &self.vals[j * VALUES..j * VALUES + 2];
        classify(v[0], v[1], self.flags[j], alpha)
    }

    /// `k_i`, the principal curvature of larger magnitude, when known.
    fn k_i(&self, j: usize) -> Option<f64> {
        let v = &self.vals[j * VALUES..j * VALUES + 2];
        let k = if v[0].abs() >= v[1].abs() { v[0] } else { v[1] };
        (self.flags[j] == 0 && k.is_finite()).then_some(f64::from(k))
    }
}

/// Section 5's vertices moved onto the crest of the curvature profile
/// (`crest.rs`); returns how far the slabs reach beyond the loaded region.
fn crests(
    cells: &mut [CellLines],
    kind: LineKind,
    grid: &BallGrid,
    tile: &TilePoints,
    slab: Slab,
) -> Result<f64, KernelError> {
    let columns = curvature_of(tile)?;
    let k_of = |j: usize| columns.k_i(j);
    let room = |p: DVec3| tile.room(p);
    let ridge = kind == LineKind::Ridge;
    Ok(cells
        .par_iter_mut()
        .map(|c| place_on_crests(&mut c.lines, ridge, grid, &k_of, slab, &room))
        .reduce(|| 0.0, f64::max))
}

/// Distance from `p` to the box `b` (0 inside; faces may be infinite).
fn gap(b: &Aabb, p: DVec3) -> f64 {
    let d = (b.min - p).max(p - b.max).max(DVec3::ZERO);
    d.length()
}

/// How far the loaded region falls short of holding everything within
/// `chain` of the owned region `own` (0 when it does).
fn uncovered(tile: &TilePoints, own: &Aabb, chain: f64) -> f64 {
    let mut short = 0.0f64;
    for a in 0..3 {
        if own.min[a].is_finite() && tile.loaded.min[a].is_finite() {
            short = short.max(tile.loaded.min[a] - (own.min[a] - chain));
        }
        if own.max[a].is_finite() && tile.loaded.max[a].is_finite() {
            short = short.max((own.max[a] + chain) - tile.loaded.max[a]);
        }
    }
    short
}

/// The lattice cell of a source point.
pub fn cell_key(p: DVec3, cell: f64) -> [i64; 3] {
    [p.x, p.y, p.z].map(|c| (c / cell).floor() as i64)
}

/// Whether the tile owns the cell of `p`: the cell's min corner lies in
/// the core, half-open.
fn owns(tile: &TilePoints, p: DVec3, cell: f64) -> bool {
    let key = cell_key(p, cell);
    (0..3).all(|a| {
        let corner = key[a] as f64 * cell;
        corner >= tile.core.min[a] && corner < tile.core.max[a]
    })
}

/// A seed's priority: its distance to the nearest kept corner, capped.
fn priority(
    s: DVec3,
    corners: Option<&BallGrid>,
    cap: f64,
    found: &mut Vec<crate::spatial::Neighbour>,
) -> f64 {
    found.clear();
    if let Some(g) = corners {
        g.within(s, cap, None, found);
    }
    let nearest = found.iter().map(|n| n.dist2).fold(f64::INFINITY, f64::min);
    nearest.sqrt().min(cap)
}

/// Section 3's corner merge for the corners whose status the tile can
/// decide (sources within `chain - (2 phi + epsilon)` of the owned region):
/// per enhanced point, `Some(true)` kept, `Some(false)` moved to the edge
/// points, `None` not decided (or no corner).
fn corner_status(
    tile: &TilePoints,
    which: &[u32],
    enh: &[Option<Enh>],
    class: &[Option<Class>],
    dist: &(impl Fn(usize) -> f64 + Sync),
    p: &Resolved,
) -> Vec<Option<bool>> {
    let mut status = vec![None; which.len()];
    for kind in [LineKind::Ridge, LineKind::Valley] {
        let mut cands = Vec::new();
        let mut at = Vec::new();
        for (e, &i) in which.iter().enumerate() {
            let same = class[i as usize].is_some_and(|c| c.kind == kind);
            if let (
                true,
                Some(Enh {
                    corner: Some((c, w)),
                    ..
                }),
            ) = (same, enh[e])
            {
                cands.push(CornerCand {
                    at: c,
                    weight: w,
                    id: tile.ids[i as usize],
                });
                at.push(e);
            }
        }
        let pos: Vec<DVec3> = cands.iter().map(|c| c.at).collect();
        let ids: Vec<u64> = cands.iter().map(|c| c.id).collect();
        let Some(grid) = BallGrid::new(&pos, &ids, p.epsilon) else {
            continue;
        };
        let decidable = p.chain() - (2.0 * p.phi + p.epsilon);
        let kept: Vec<Option<bool>> = (0..cands.len())
            .into_par_iter()
            .map(|c| {
                let src = which[at[c]] as usize;
                (dist(src) <= decidable).then(|| corner_kept(c, &cands, &grid, p.epsilon))
            })
            .collect();
        for (c, k) in kept.into_iter().enumerate() {
            status[at[c]] = k;
        }
    }
    status
}

/// One kind's enhanced points: edge points (the enhancement's, and corners
/// moved by the merge) and kept corners, with their source points.
struct Entries {
    pos: Vec<DVec3>,
    /// Tie keys: `2 id` for an edge point, `2 id + 1` for a moved corner.
    ids: Vec<u64>,
    source: Vec<u32>,
    /// Whether the entry is the enhancement's own edge point.
    own_edge: Vec<bool>,
    corners: Corners,
}

#[derive(Default)]
struct Corners {
    pos: Vec<DVec3>,
    ids: Vec<u64>,
    source: Vec<u32>,
}

impl Entries {
    fn collect(
        tile: &TilePoints,
        which: &[u32],
        enh: &[Option<Enh>],
        class: &[Option<Class>],
        status: &[Option<bool>],
        kind: LineKind,
    ) -> Entries {
        let mut e = Entries {
            pos: Vec::new(),
            ids: Vec::new(),
            source: Vec::new(),
            own_edge: Vec::new(),
            corners: Corners::default(),
        };
        for (k, &i) in which.iter().enumerate() {
            let (Some(c), Some(x)) = (class[i as usize], enh[k]) else {
                continue;
            };
            if c.kind != kind {
                continue;
            }
            let id = tile.ids[i as usize];
            e.push(x.edge, 2 * id, i, true);
            match (x.corner, status[k]) {
                (Some((at, _)), Some(false)) => e.push(at, 2 * id + 1, i, false),
                (Some((at, _)), Some(true)) => {
                    e.corners.pos.push(at);
                    e.corners.ids.push(id);
                    e.corners.source.push(i);
                }
                _ => {}
            }
        }
        e
    }

    fn push(&mut self, at: DVec3, id: u64, source: u32, own_edge: bool) {
        self.pos.push(at);
        self.ids.push(id);
        self.source.push(source);
        self.own_edge.push(own_edge);
    }

    /// Section 4 for the entries whose sources lie within the corner cap
    /// of the owned region (the rest are only neighbours); `None` for the
    /// others and for noise.
    fn smooth(&self, dist: &impl Fn(usize) -> f64, p: &Resolved) -> Vec<Option<DVec3>> {
        // Cells of the first radius: most points settle there.
        let Some(grid) = BallGrid::new(&self.pos, &self.ids, p.smooth_cell()) else {
            return vec![None; self.pos.len()];
        };
        let cgrid = BallGrid::new(&self.corners.pos, &self.corners.ids, p.smooth_cell());
        let which: Vec<u32> = (0..self.pos.len())
            .filter(|&e| dist(self.source[e] as usize) <= p.corner_cap())
            .map(|e| e as u32)
            .collect();
        let done = smooth_points(
            &which,
            &self.pos,
            &grid,
            &self.corners.pos,
            cgrid.as_ref(),
            p,
        );
        let mut out = vec![None; self.pos.len()];
        for (&e, s) in which.iter().zip(done) {
            out[e as usize] = s;
        }
        out
    }

    /// Adds this kind's counts over the owned cells' points.
    fn count(
        &self,
        kind: LineKind,
        smoothed: &[Option<DVec3>],
        owned: &impl Fn(usize) -> bool,
        c: &mut FeatureCounts,
    ) {
        let k = kind_slot(kind);
        for (e, &src) in self.source.iter().enumerate() {
            if owned(src as usize) {
                c.enhanced[k] += u64::from(self.own_edge[e]);
                c.smoothed[k] += u64::from(smoothed[e].is_some());
            }
        }
        c.corners[k] += self
            .corners
            .source
            .iter()
            .filter(|&&s| owned(s as usize))
            .count() as u64;
    }
}

/// A cell's smoothed edge points: position, tie key, seed priority.
type CellPoints = Vec<(DVec3, u64, f64)>;

/// Grows each cell's polylines (cells in parallel, each on its own).
fn grow_cells(
    groups: BTreeMap<[i64; 3], CellPoints>,
    kind: LineKind,
    p: &Resolved,
) -> Vec<CellLines> {
    let groups: Vec<([i64; 3], CellPoints)> = groups.into_iter().collect();
    groups
        .into_par_iter()
        .map(|(key, pts)| {
            let pos: Vec<DVec3> = pts.iter().map(|p| p.0).collect();
            let ids: Vec<u64> = pts.iter().map(|p| p.1).collect();
            let prio: Vec<f64> = pts.iter().map(|p| p.2).collect();
            CellLines {
                key,
                kind,
                lines: grow_polylines(&pos, &ids, &prio, p.gamma_max, (p.refine, p.refine_width)),
            }
        })
        .collect()
}
