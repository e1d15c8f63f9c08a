//! Six-source orientation of a store whose union-find does not fit the
//! memory budget: the same flips as [`super::tiled`]'s in-memory pass, from
//! the labels [`ForestLabels`] leaves on disk (the sources joined first to
//! its virtual root, as there).
//!
//! A component the sources do not reach is rooted at its extreme point
//! along the first source direction. For a component inside one tile that
//! point is found when the tile is read, and found again in the write pass;
//! only components that may span tiles keep theirs in memory.

use super::state::faces_away;
use super::Extreme;
use crate::normals::labels::ForestLabels;
use crate::normals::orient::rewrite_signs;
use crate::normals::runs::EdgeRuns;
use crate::normals::{NormalsError, FLAG_DEGENERATE};
use crate::pipeline::Progress;
use crate::store::{Column, PointStore, TileEntry};
use glam::DVec3;
use std::collections::BTreeMap;

/// A component's extreme point along the direction so far: its extent,
/// its id, and the flip that makes its normal face the direction.
#[derive(Clone, Copy, Debug)]
struct Best {
    extent: f64,
    id: u64,
    flip: bool,
}

impl Best {
    fn absorb(slot: &mut Option<Best>, b: Best) {
        match slot {
            Some(a)
                if (a.extent, std::cmp::Reverse(a.id)) >= (b.extent, std::cmp::Reverse(b.id)) => {}
            _ => *slot = Some(b),
        }
    }
}

/// Orients the normal column from the forests in `runs` and the `sources`
/// (each with its flip); returns the components oriented and the points
/// left unoriented.
pub(super) fn orient_external(
    store: &PointStore,
    mut runs: EdgeRuns,
    sources: &[(Extreme, bool)],
    dir: DVec3,
    normals: &Column,
    flags: &Column,
    progress: &dyn Progress,
) -> Result<(usize, u64), NormalsError> {
    let extra: Vec<(u32, bool)> = sources.iter().map(|(e, f)| (e.index as u32, *f)).collect();
    let labels = ForestLabels::solve(store, &mut runs, &extra, progress)?;
    drop(runs);
    let reached = labels.root();
    let mut spanning: Vec<Option<Best>> = vec![None; labels.node_components];
    let mut components = usize::from(!sources.is_empty());
    for t in store.tiles() {
        for (label, b) in tile_bests(store, t, &labels, dir, normals, flags)? {
            if Some(label) == reached.map(|r| r.0) {
                continue;
            }
            match labels.node_component(label) {
                Some(k) => Best::absorb(&mut spanning[k], b),
                None => components += 1,
            }
        }
    }
    components += spanning.iter().filter(|b| b.is_some()).count();
    progress.begin("orient: write", store.len());
    let mut unoriented = 0;
    for t in store.tiles() {
        let local = tile_bests(store, t, &labels, dir, normals, flags)?;
        let mut words = Vec::new();
        labels.read_tile(t, &mut words)?;
        unoriented += rewrite_signs(t, normals, flags, |i| {
            let w = words[(i - t.start) as usize];
            let (label, parity) = (w & !(1 << 63), w >> 63 == 1);
            match reached {
                Some((root, root_parity)) if root == label => Some(parity ^ root_parity),
                _ => match labels.node_component(label) {
                    Some(k) => spanning[k].map(|b| parity ^ b.flip),
                    None => local.get(&label).map(|b| parity ^ b.flip),
                },
            }
        })?;
        progress.advance(t.count);
    }
    progress.end();
    Ok((components, unoriented))
}

/// Tile `t`'s extreme point along `dir` per label (flips relative to the
/// label's frame), over the points with a usable normal.
fn tile_bests(
    store: &PointStore,
    t: &TileEntry,
    labels: &ForestLabels,
    dir: DVec3,
    normals: &Column,
    flags: &Column,
) -> Result<BTreeMap<u64, Best>, NormalsError> {
    let (mut pts, mut ids, mut nrm, mut flg, mut words) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new());
    store.read_points(t.start, t.count, &mut pts)?;
    store.read_indices(t.start, t.count, &mut ids)?;
    normals.read_f32(t.start, t.count, &mut nrm)?;
    flags.read_u8(t.start, t.count, &mut flg)?;
    labels.read_tile(t, &mut words)?;
    let mut best: BTreeMap<u64, Option<Best>> = BTreeMap::new();
    for (k, p) in pts.iter().enumerate() {
        let n = crate::normals::normal_at(&nrm, k);
        if flg[k] & FLAG_DEGENERATE != 0 || n == DVec3::ZERO {
            continue;
        }
        let (label, parity) = (words[k] & !(1 << 63), words[k] >> 63 == 1);
        let b = Best {
            extent: p.dot(dir),
            id: ids[k],
            flip: parity ^ faces_away(n, dir),
        };
        Best::absorb(best.entry(label).or_default(), b);
    }
    Ok(best
        .into_iter()
        .filter_map(|(l, b)| b.map(|b| (l, b)))
        .collect())
}
