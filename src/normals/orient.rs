//! Global orientation from the merged tile forests (paper 1 section 2.4).
//!
//! 1. Kruskal over the union of the tiles' minimum spanning forests, in
//!    global edge order, with a parity union-find: each point learns whether
//!    it flips relative to its component's root.
//! 2. Per component, the paper's root rule: its highest point (largest z,
//!    ties to the smallest id) gets `n . (0,0,1) > 0`.
//! 3. The paper's island rule: if fewer than 1/1000 of the points lie outside
//!    the component of the highest point, they stay unoriented (flagged).
//!    Deviation: otherwise the paper restarts Prim's walk from the unreached
//!    point nearest the reached set, carrying the sign across that gap; here
//!    each further component (largest first) is rooted at its own highest
//!    point, until the points left are fewer than 1/1000. Finding the nearest
//!    point across components needs a global search the tiles do not give.

use super::runs::EdgeRuns;
use super::unionfind::ParityUnionFind;
use super::{NormalsError, FLAG_DEGENERATE, FLAG_UNORIENTED};
use crate::pipeline::Progress;
use crate::store::{Column, PointStore};
use std::collections::HashMap;

#[derive(Clone, Copy, Debug, Default)]
pub struct OrientStats {
    pub components: usize,
    pub oriented_components: usize,
    pub unoriented: u64,
}

/// Per-component facts gathered in one pass.
#[derive(Clone, Copy, Debug)]
struct Component {
    size: u64,
    top_z: f32,
    top_id: u64,
    /// Flip every member's parity by this to make the top point face +z.
    sign: bool,
}

pub fn orient_by_forest(
    store: &PointStore,
    runs: EdgeRuns,
    normals: &Column,
    flags: &Column,
    progress: &dyn Progress,
) -> Result<OrientStats, NormalsError> {
    let mut uf = ParityUnionFind::new(store.len() as usize);
    runs.union_all(&mut uf, "orient: spanning tree", progress)?;
    let comps = components(store, &mut uf, normals, flags, progress)?;
    let oriented = island_rule(&comps);
    let unoriented = apply(store, &mut uf, &oriented, normals, flags, progress)?;
    Ok(OrientStats {
        components: comps.len(),
        oriented_components: oriented.len(),
        unoriented,
    })
}

/// Visits every tile's points with their input ids, normals and flags.
fn for_each_tile(
    store: &PointStore,
    normals: &Column,
    flags: &Column,
    mut f: impl FnMut(u64, &[glam::DVec3], &[u64], &mut [f32], &mut [u8]) -> Result<bool, NormalsError>,
) -> Result<(), NormalsError> {
    let (mut pts, mut ids, mut nrm, mut flg) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for t in store.tiles() {
        store.read_points(t.start, t.count, &mut pts)?;
        store.read_indices(t.start, t.count, &mut ids)?;
        normals.read_f32(t.start, t.count, &mut nrm)?;
        flags.read_u8(t.start, t.count, &mut flg)?;
        if f(t.start, &pts, &ids, &mut nrm, &mut flg)? {
            normals.write_f32(t.start, &nrm)?;
            flags.write_bytes(t.start, &flg)?;
        }
    }
    Ok(())
}

fn components(
    store: &PointStore,
    uf: &mut ParityUnionFind,
    normals: &Column,
    flags: &Column,
    progress: &dyn Progress,
) -> Result<HashMap<u32, Component>, NormalsError> {
    let mut comps: HashMap<u32, Component> = HashMap::new();
    progress.begin("orient: components", store.len());
    for_each_tile(store, normals, flags, |_, pts, ids, nrm, flg| {
        for i in 0..pts.len() {
            if flg[i] & FLAG_DEGENERATE != 0 {
                continue;
            }
            let (root, parity) = uf.find(ids[i] as u32);
            let z = pts[i].z as f32;
            let sign = parity ^ (nrm[3 * i + 2] < 0.0);
            let c = comps.entry(root).or_insert(Component {
                size: 0,
                top_z: z,
                top_id: ids[i],
                sign,
            });
            c.size += 1;
            if (z, std::cmp::Reverse(ids[i])) > (c.top_z, std::cmp::Reverse(c.top_id)) {
                c.top_z = z;
                c.top_id = ids[i];
                c.sign = sign;
            }
        }
        progress.advance(pts.len() as u64);
        Ok(false)
    })?;
    progress.end();
    Ok(comps)
}

/// Roots to orient, with their sign, by the island rule.
fn island_rule(comps: &HashMap<u32, Component>) -> HashMap<u32, bool> {
    let total: u64 = comps.values().map(|c| c.size).sum();
    let mut order: Vec<(&u32, &Component)> = comps.iter().collect();
    // The component of the highest point first, then by size.
    let first = order
        .iter()
        .max_by(|a, b| {
            (a.1.top_z, std::cmp::Reverse(a.1.top_id))
                .partial_cmp(&(b.1.top_z, std::cmp::Reverse(b.1.top_id)))
                .unwrap_or(std::cmp::Ordering::Equal)
        })
        .map(|(r, _)| **r);
    order.sort_by_key(|(r, c)| (Some(**r) != first, std::cmp::Reverse(c.size), **r));
    let mut oriented = HashMap::new();
    let mut left = total;
    for (root, c) in order {
        if !oriented.is_empty() && left * 1000 < total {
            break;
        }
        oriented.insert(*root, c.sign);
        left -= c.size;
    }
    oriented
}

fn apply(
    store: &PointStore,
    uf: &mut ParityUnionFind,
    oriented: &HashMap<u32, bool>,
    normals: &Column,
    flags: &Column,
    progress: &dyn Progress,
) -> Result<u64, NormalsError> {
    let mut unoriented = 0;
    progress.begin("orient: write", store.len());
    for_each_tile(store, normals, flags, |_, pts, ids, nrm, flg| {
        for i in 0..pts.len() {
            if flg[i] & FLAG_DEGENERATE != 0 {
                continue;
            }
            let (root, parity) = uf.find(ids[i] as u32);
            match oriented.get(&root) {
                Some(sign) if parity ^ sign => {
                    nrm[3 * i..3 * i + 3].iter_mut().for_each(|v| *v = -*v)
                }
                Some(_) => {}
                None => {
                    flg[i] |= FLAG_UNORIENTED;
                    unoriented += 1;
                }
            }
        }
        progress.advance(pts.len() as u64);
        Ok(true)
    })?;
    progress.end();
    Ok(unoriented)
}
