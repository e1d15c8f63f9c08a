//! Global orientation from the merged tile forests (paper 1 section 2.4).
//!
//! 1. Kruskal over the union of the tiles' minimum spanning forests, in
//!    global edge order, with a parity union-find: each point learns whether
//!    it flips relative to its component's root.
//! 2. Per component, the paper's root rule: its highest point (largest z,
//!    ties to the smallest id) gets `n . (0,0,1) > 0`.
//! 3. The paper's island rule: if fewer than 1/1000 of the points lie outside
//!    the component of the highest point, they stay unoriented (flagged).
//!    Deviation: each such island is still signed by its own root rule
//!    ([`Sign::Island`]), flagged all the same, so a consumer that can take
//!    an island apart may: the 1M dragon's 102-point filament is one, and
//!    a reconstruction that dropped it missed the filament by 33 spacings.
//!    Deviation: otherwise the paper restarts Prim's walk from the unreached
//!    point nearest the reached set, carrying the sign across that gap; here
//!    each further component (largest first) is rooted at its own highest
//!    point, until the points left are fewer than 1/1000. Finding the nearest
//!    point across components needs a global search the tiles do not give.
//!
//! The union-find is indexed by store index, not input id (edges carry both,
//! see [`super::forest::Edge`]): the store is in spatial order, so its
//! accesses stay local. After step 1 it is flattened into dense component
//! labels (`Components`), so steps 2 and 3 are sequential array reads over
//! the tiles, in parallel; per-component facts live in a `Vec` by label.
//! Every per-component fact is order-free (a count, and a maximum under a
//! total order over input ids), so neither the thread count nor the tiling
//! (which moves store indices, labels and roots) can change a result.

mod external;

pub use external::orient_external;

use super::components::Components;
use super::runs::EdgeRuns;
use super::unionfind::ParityUnionFind;
use super::{NormalsError, FLAG_DEGENERATE, FLAG_UNORIENTED};
use crate::pipeline::Progress;
use crate::store::{Column, PointStore, TileEntry};
use rayon::prelude::*;
use std::cmp::Reverse;
use std::collections::HashMap;

/// Memory per point of the in-memory pass: the union-find's parent (4),
/// rank (1) and parity bit, rounded up.
pub const BYTES_PER_POINT: u64 = 6;

#[derive(Clone, Copy, Debug, Default)]
pub struct OrientStats {
    pub components: usize,
    pub unoriented: u64,
}

/// Per-component facts (over non-degenerate points; ids fit u32, see
/// `store::build::MAX_POINTS`).
#[derive(Clone, Copy, Debug, Default)]
struct Component {
    size: u32,
    top_z: f32,
    top_id: u32,
    /// Flip every member's parity by this to make the top point face +z.
    sign: bool,
}

impl Component {
    /// Joins the facts of two disjoint sets of the same component.
    fn absorb(&mut self, o: &Component) {
        if o.size == 0 {
            return;
        }
        if self.size == 0 || (o.top_z, Reverse(o.top_id)) > (self.top_z, Reverse(self.top_id)) {
            (self.top_z, self.top_id, self.sign) = (o.top_z, o.top_id, o.sign);
        }
        self.size += o.size;
    }
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
    progress.begin("orient: components", store.len());
    let comps = uf.into_components();
    let facts = components(store, &comps, normals, flags, progress)?;
    progress.end();
    let reached = island_rule(&facts);
    let unoriented = apply(store, &comps, &facts, &reached, normals, flags, progress)?;
    Ok(OrientStats {
        components: facts.iter().filter(|c| c.size > 0).count(),
        unoriented,
    })
}

/// Facts of every component, by label (size 0: only degenerate members).
fn components(
    store: &PointStore,
    comps: &Components,
    normals: &Column,
    flags: &Column,
    progress: &dyn Progress,
) -> Result<Vec<Component>, NormalsError> {
    let partials: Vec<Vec<(u64, Component)>> = store
        .tiles()
        .par_iter()
        .map(|t| {
            let part = tile_components(store, t, normals, flags, |i| {
                let (label, parity) = comps.get(i as u32);
                (u64::from(label), parity)
            });
            progress.advance(t.count);
            part
        })
        .collect::<Result<_, _>>()?;
    let mut facts = vec![Component::default(); comps.count()];
    for (label, c) in partials.iter().flatten() {
        facts[*label as usize].absorb(c);
    }
    Ok(facts)
}

/// One tile's share of the component facts, one entry per label it meets,
/// in order of first appearance; `label_of(store index)` gives a point's
/// component label and parity.
fn tile_components(
    store: &PointStore,
    t: &TileEntry,
    normals: &Column,
    flags: &Column,
    label_of: impl Fn(u64) -> (u64, bool),
) -> Result<Vec<(u64, Component)>, NormalsError> {
    let (mut xyz, mut ids, mut nrm, mut flg) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    store.read_coords(t.start, t.count, &mut xyz)?;
    store.read_indices(t.start, t.count, &mut ids)?;
    normals.read_f32(t.start, t.count, &mut nrm)?;
    flags.read_u8(t.start, t.count, &mut flg)?;
    let mut part: Vec<(u64, Component)> = Vec::new();
    // Neighbouring points nearly always share a component: the map is
    // consulted only when the label changes.
    let mut slot_of: HashMap<u64, usize> = HashMap::new();
    let mut last: Option<(u64, usize)> = None;
    for (i, &id) in ids.iter().enumerate() {
        if flg[i] & FLAG_DEGENERATE != 0 {
            continue;
        }
        let (label, parity) = label_of(t.start + i as u64);
        let slot = match last {
            Some((l, s)) if l == label => s,
            _ => *slot_of.entry(label).or_insert_with(|| {
                part.push((label, Component::default()));
                part.len() - 1
            }),
        };
        last = Some((label, slot));
        part[slot].1.absorb(&Component {
            size: 1,
            top_z: xyz[3 * i + 2],
            top_id: id as u32,
            sign: parity ^ (nrm[3 * i + 2] < 0.0),
        });
    }
    Ok(part)
}

/// Whether the island rule orients each component (by label) with the
/// rest; the others are islands, signed by their own root rule.
fn island_rule(facts: &[Component]) -> Vec<bool> {
    let total: u64 = facts.iter().map(|c| u64::from(c.size)).sum();
    let mut order: Vec<u32> = (0..facts.len() as u32)
        .filter(|&l| facts[l as usize].size > 0)
        .collect();
    let key = |l: u32| {
        let c = &facts[l as usize];
        (c.top_z, Reverse(c.top_id))
    };
    // The component of the highest point first, then by size.
    let first = order.iter().copied().max_by(|&a, &b| {
        key(a)
            .partial_cmp(&key(b))
            .unwrap_or(std::cmp::Ordering::Equal)
    });
    order.sort_by_key(|&l| {
        let c = &facts[l as usize];
        (Some(l) != first, Reverse(c.size), c.top_id)
    });
    let mut reached = vec![false; facts.len()];
    let mut left = total;
    for (n, l) in order.into_iter().enumerate() {
        if n > 0 && left * 1000 < total {
            break;
        }
        reached[l as usize] = true;
        left -= u64::from(facts[l as usize].size);
    }
    reached
}

/// Flips or flags every tile's normals (tiles in parallel: disjoint ranges);
/// returns the number of unoriented points.
fn apply(
    store: &PointStore,
    comps: &Components,
    facts: &[Component],
    reached: &[bool],
    normals: &Column,
    flags: &Column,
    progress: &dyn Progress,
) -> Result<u64, NormalsError> {
    progress.begin("orient: write", store.len());
    let counts: Vec<u64> = store
        .tiles()
        .par_iter()
        .map(|t| {
            let n = rewrite_signs(t, normals, flags, |i| {
                let (label, parity) = comps.get(i as u32);
                let c = &facts[label as usize];
                match reached[label as usize] {
                    true => Sign::Reached(parity ^ c.sign),
                    false => Sign::Island(parity ^ c.sign),
                }
            });
            progress.advance(t.count);
            n
        })
        .collect::<Result<_, _>>()?;
    progress.end();
    Ok(counts.iter().sum())
}

/// What an orientation says of one point's normal.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Sign {
    /// The orientation reached it: flip the normal (`true`) or keep it.
    Reached(bool),
    /// An island the paper's rule leaves out: flagged unoriented (its sign
    /// is not tied to the rest), but signed by its own root rule, so a
    /// consumer that takes islands apart (an open reconstruction) can.
    Island(bool),
    /// Not reached: flagged unoriented, the normal's sign left as it was.
    Unreached,
}

impl From<Option<bool>> for Sign {
    fn from(flip: Option<bool>) -> Self {
        flip.map_or(Sign::Unreached, Sign::Reached)
    }
}

/// Rewrites tile `t`'s normals and flags in the store: `sign(store index)`
/// says whether a non-degenerate point's normal flips and whether it is
/// flagged unoriented ([`Sign`]; `Option<bool>` reads `None` as
/// unreached). Returns the number flagged. Shared by every orientation
/// mode's final pass.
pub(super) fn rewrite_signs<S: Into<Sign>>(
    t: &TileEntry,
    normals: &Column,
    flags: &Column,
    mut sign: impl FnMut(u64) -> S,
) -> Result<u64, NormalsError> {
    let (mut nrm, mut flg) = (Vec::new(), Vec::new());
    normals.read_f32(t.start, t.count, &mut nrm)?;
    flags.read_u8(t.start, t.count, &mut flg)?;
    let mut unoriented = 0;
    for i in 0..flg.len() {
        if flg[i] & FLAG_DEGENERATE != 0 {
            continue;
        }
        let (flip, reached) = match sign(t.start + i as u64).into() {
            Sign::Reached(flip) => (flip, true),
            Sign::Island(flip) => (flip, false),
            Sign::Unreached => (false, false),
        };
        if flip {
            nrm[3 * i..3 * i + 3].iter_mut().for_each(|v| *v = -*v);
        }
        if !reached {
            flg[i] |= FLAG_UNORIENTED;
            unoriented += 1;
        }
    }
    normals.write_f32(t.start, &nrm)?;
    flags.write_bytes(t.start, &flg)?;
    Ok(unoriented)
}
