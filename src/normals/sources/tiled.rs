//! Six-source orientation of a whole store, tile by tile, exact:
//!
//! 1. One pass over the store finds the sources of the whole cloud.
//! 2. The tile kernel ([`super::kernel`]) returns each tile's minimum
//!    spanning forest of pairs; the forests go to disk as sorted runs.
//! 3. Kruskal over the merged runs with a parity union-find, after joining
//!    every source to one extra root with its own flip (its normal must
//!    face its direction). A point's flip is its parity relative to that
//!    root: the best-first propagation's result, since both are the
//!    parities along the same unique forest (ties broken by ids).
//! 4. A component the sources do not reach is rooted at its extreme point
//!    along the first source direction, which faces that way
//!    ([`super::propagate`]); then the oriented normals are written into
//!    the store column. Every point with a normal ends up oriented, so
//!    [`FLAG_UNORIENTED`](crate::normals::FLAG_UNORIENTED) marks none here (degenerate points keep their
//!    [`FLAG_DEGENERATE`] and zero normal).
//!
//! Memory: the union-find holds 5 bytes and a bit per point, as the
//! spanning-tree pass does; the forests (about one edge per point) stay on
//! disk. Like that pass, the union-find is indexed by store index. When it
//! does not fit the memory promise, `super::external` gives the same
//! flips from the contracted forests.

use super::external::orient_external;
use super::kernel::SourcesKernel;
use super::state::faces_away;
use super::{Extreme, Extremes, Neighbourhood, Order, SourceParams, Sources, SourcesError};
use crate::normals::orient::anchors::Anchoring;
use crate::normals::orient::{rewrite_signs, BYTES_PER_POINT};
use crate::normals::runs::{EdgeRuns, Layout};
use crate::normals::unionfind::ParityUnionFind;
use crate::normals::{initial_margin, NormalsError, FLAG_DEGENERATE};
use crate::pipeline::{run_tiles, Progress, RunOptions};
use crate::store::{Column, PointStore};
use glam::DVec3;
use std::collections::HashMap;

/// Least `|n . direction|` of a single source's anchors: within 45.6
/// degrees of its direction.
const SOURCE_ANCHOR_COS: f32 = 0.7;

/// Scratch file of the tiles' forests (removed when done).
const FOREST_FILE: &str = ".sources.edges";

/// What the tiled six-source orientation did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SourceStats {
    /// Sources of the whole cloud (up to six, coincident ones once).
    pub sources: usize,
    /// Forest edges over all tiles.
    pub forest_edges: u64,
    /// Components the sources reach (1, or 0 without normals) plus those
    /// rooted on their own.
    pub components: usize,
    /// Points with a normal the propagation did not reach.
    pub unoriented: u64,
}

/// First margin to try: the neighbourhood radius or the reach of the k
/// nearest, whichever is larger (the kernel asks for more when short).
pub fn tile_margin(params: &SourceParams, spacing: f64) -> f64 {
    let k = match params.hood {
        Neighbourhood::Radius(_) => params.bridge_k,
        Neighbourhood::Nearest(k) => k,
    };
    let r = match params.hood {
        Neighbourhood::Radius(r) => r,
        Neighbourhood::Nearest(_) => 0.0,
    };
    r.max(if k > 0 {
        initial_margin(spacing, k)
    } else {
        0.0
    })
}

/// Orients the store's normal column (PCA normals, any sign) in place.
pub fn orient_store(
    store: &PointStore,
    params: &SourceParams,
    spacing: f64,
    opts: RunOptions,
    progress: &dyn Progress,
    normals: &Column,
    flags: &Column,
) -> Result<SourceStats, NormalsError> {
    params.validate()?;
    if params.order == Order::Stacks {
        return Err(SourcesError::StacksNotTiled.into());
    }
    if store.len() >= u32::MAX as u64 {
        return Err(SourcesError::IdTooLarge { id: store.len() }.into());
    }
    let sources = global_sources(store, params, normals, flags)?;
    let kernel = SourcesKernel {
        params: *params,
        margin: tile_margin(params, spacing),
    };
    let external = !opts.holds(store.len() + 1, BYTES_PER_POINT);
    let mut runs = EdgeRuns::create(
        &store.dir().join(FOREST_FILE),
        Layout::for_orientation(external),
    )?;
    // A single source stands for its direction, not for one point: every
    // normal within 45 degrees of it is an anchor facing it, tied to the
    // root before any pair (`orient::anchors`, cost 0). Deviation from
    // paper 5, whose one source point (on aerial data the top of a tree,
    // its normal noise) signed everything it reached: 99.2 % of autzen's
    // ground faced down, 0.01 % now. The pairs carry the sign to the
    // steeper rest as before. Measured at least |n.d| 0.5 / 0.7 / 0.9: the
    // test terrain's normals agreeing with the true surface 99.9450 /
    // 99.9965 / 99.9965 % (99.9965 % before), autzen's ground up 100.00 /
    // 99.99 / 99.96 %, lidR's Megaplot 97.12 / 96.67 / 95.64 %.
    let anchoring = match params.sources {
        Sources::Single(d) => {
            Anchoring::new(d, store.len()).map(|a| a.with(SOURCE_ANCHOR_COS, 0.0))
        }
        Sources::Six => None,
    };
    let (mut ids, mut nrm, mut flg) = (Vec::new(), Vec::new(), Vec::new());
    run_tiles(store, &kernel, opts, progress, |t, forest| {
        let tile = &store.tiles()[t];
        let core = tile.start..tile.start + tile.count;
        ids.clear();
        if anchoring.is_some() || external {
            store.read_indices(tile.start, tile.count, &mut ids)?;
        }
        let forest = match &anchoring {
            Some(a) => {
                normals.read_f32(tile.start, tile.count, &mut nrm)?;
                flags.read_u8(tile.start, tile.count, &mut flg)?;
                a.forest(forest, core.clone(), &ids, &nrm, &flg)
            }
            None => forest,
        };
        runs.push_tile_run(&forest, core, &ids).map_err(Into::into)
    })?;
    let mut stats = SourceStats {
        sources: sources.len(),
        forest_edges: runs.edges(),
        ..SourceStats::default()
    };
    if external {
        let dir = params.first_direction();
        (stats.components, stats.unoriented) =
            orient_external(store, runs, &sources, dir, normals, flags, progress)?;
        return Ok(stats);
    }
    let root = store.len() as u32;
    let mut uf = ParityUnionFind::new(store.len() as usize + 1);
    for &(e, flip) in &sources {
        uf.union(e.index as u32, root, flip);
    }
    runs.union_all(&mut uf, "orient: six sources, forest", progress)?;
    let roots = component_roots(
        store,
        params.first_direction(),
        &mut uf,
        root,
        normals,
        flags,
    )?;
    stats.components = roots.len() + usize::from(!sources.is_empty());
    stats.unoriented = write_oriented(store, &mut uf, root, &roots, normals, flags, progress)?;
    Ok(stats)
}

/// The sources of the whole cloud over the points with a usable normal,
/// each with whether its normal must flip to face its direction.
fn global_sources(
    store: &PointStore,
    params: &SourceParams,
    normals: &Column,
    flags: &Column,
) -> Result<Vec<(Extreme, bool)>, NormalsError> {
    let mut ex = Extremes::new(&params.sources);
    let mut found: HashMap<u64, DVec3> = HashMap::new();
    for_each_tile(store, normals, flags, |start, pts, ids, nrm, _| {
        for (k, p) in pts.iter().enumerate() {
            if let Some(n) = nrm[k] {
                ex.offer(*p, ids[k], start + k as u64);
                found.insert(ids[k], n);
            }
        }
        // Keep only the current leaders' normals: memory stays tiny.
        let leaders: Vec<u64> = ex.finish().iter().map(|e| e.id).collect();
        found.retain(|id, _| leaders.contains(id));
        Ok(())
    })?;
    Ok(ex
        .finish()
        .into_iter()
        .filter_map(|e| found.get(&e.id).map(|n| (e, faces_away(*n, e.direction))))
        .collect())
}

/// Per component the sources do not reach: its flip relative to its
/// union-find root, set by its extreme point along `dir`.
fn component_roots(
    store: &PointStore,
    dir: DVec3,
    uf: &mut ParityUnionFind,
    root: u32,
    normals: &Column,
    flags: &Column,
) -> Result<HashMap<u32, bool>, NormalsError> {
    // Per root: (extent along dir, id, flip) of the best point so far.
    let mut best: HashMap<u32, (f64, u64, bool)> = HashMap::new();
    for_each_tile(store, normals, flags, |start, pts, ids, nrm, _| {
        let reached = uf.find(root).0;
        for (k, p) in pts.iter().enumerate() {
            let Some(n) = nrm[k] else { continue };
            let (r, parity) = uf.find((start + k as u64) as u32);
            if r == reached {
                continue;
            }
            let s = p.dot(dir);
            let flip = parity ^ faces_away(n, dir);
            let b = best.entry(r).or_insert((s, ids[k], flip));
            if s > b.0 || (s == b.0 && ids[k] < b.1) {
                *b = (s, ids[k], flip);
            }
        }
        Ok(())
    })?;
    Ok(best.into_iter().map(|(r, b)| (r, b.2)).collect())
}

/// Writes every point's oriented normal; returns the points left unoriented.
fn write_oriented(
    store: &PointStore,
    uf: &mut ParityUnionFind,
    root: u32,
    roots: &HashMap<u32, bool>,
    normals: &Column,
    flags: &Column,
    progress: &dyn Progress,
) -> Result<u64, NormalsError> {
    progress.begin("orient: write", store.len());
    let mut unoriented = 0;
    for t in store.tiles() {
        let (reached, root_parity) = uf.find(root);
        unoriented += rewrite_signs(t, normals, flags, |i| {
            let (r, parity) = uf.find(i as u32);
            if r == reached {
                Some(parity ^ root_parity)
            } else {
                roots.get(&r).map(|s| parity ^ s)
            }
        })?;
        progress.advance(t.count);
    }
    progress.end();
    Ok(unoriented)
}

/// Visits every tile's points, ids and usable normals.
fn for_each_tile(
    store: &PointStore,
    normals: &Column,
    flags: &Column,
    mut f: impl FnMut(u64, &[DVec3], &[u64], &[Option<DVec3>], &[u8]) -> Result<(), NormalsError>,
) -> Result<(), NormalsError> {
    let (mut pts, mut ids, mut nrm, mut flg) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let mut usable = Vec::new();
    for t in store.tiles() {
        store.read_points(t.start, t.count, &mut pts)?;
        store.read_indices(t.start, t.count, &mut ids)?;
        normals.read_f32(t.start, t.count, &mut nrm)?;
        flags.read_u8(t.start, t.count, &mut flg)?;
        usable.clear();
        usable.extend(nrm.chunks_exact(3).zip(&flg).map(|(n, f)| {
            let n = DVec3::new(n[0] as f64, n[1] as f64, n[2] as f64);
            (f & FLAG_DEGENERATE == 0 && n != DVec3::ZERO).then_some(n)
        }));
        f(t.start, &pts, &ids, &usable, &flg)?;
    }
    Ok(())
}
