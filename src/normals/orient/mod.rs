//! Global orientation from the merged tile forests (paper 1 section 2.4).
//!
//! 1. Kruskal over the union of the tiles' minimum spanning forests, in
//!    global edge order, with a parity union-find: each point learns whether
//!    it flips relative to its component's root.
//! 2. Per component, the sign. Deviation: paper 1 turns the normal of the
//!    highest point (largest z) to face +z; here the highest points of each
//!    column of a grid over the cloud vote, isolated outliers left out
//!    ([`vote`] says why). With aerial anchors ([`anchors`]) the component
//!    of the sky faces as its anchors do, and comes first.
//! 3. The paper's island rule: if fewer than 1/1000 of the points lie outside
//!    the component of the highest point, they stay unoriented (flagged).
//!    Deviation: each such island is still signed by its own vote
//!    ([`Sign::Island`]), flagged all the same, so a consumer that can take
//!    an island apart may: the 1M dragon's 102-point filament is one, and
//!    a reconstruction that dropped it missed the filament by 33 spacings.
//!    Deviation: otherwise the paper restarts Prim's walk from the unreached
//!    point nearest the reached set, carrying the sign across that gap; here
//!    each further component (largest first) is signed by its own vote,
//!    until the points left are fewer than 1/1000. Finding the nearest
//!    point across components needs a global search the tiles do not give.
//!    The "highest point" of the island rule is the highest that is not an
//!    isolated outlier ([`vote::Rank`]).
//!
//! The union-find is indexed by store index, not input id (edges carry both,
//! see [`super::forest::Edge`]): the store is in spatial order, so its
//! accesses stay local. After step 1 it is flattened into dense component
//! labels (`Components`), so steps 2 and 3 are sequential array reads over
//! the tiles, in parallel; per-component facts live in a `Vec` by label.
//! Every per-component fact is order-free (a count, a maximum under a total
//! order over input ids, the largest under it per column), so neither the thread
//! count nor the tiling (which moves store indices, labels and roots) can
//! change a result.

pub(crate) mod anchors;
mod external;
pub(crate) mod isolated;
mod vote;

pub use external::orient_external;
pub(crate) use isolated::Isolated;
pub(crate) use vote::ColumnGrid;
use vote::{Rank, Voter, Voters};

use super::components::Components;
use super::runs::EdgeRuns;
use super::unionfind::ParityUnionFind;
use super::{NormalsError, FLAG_DEGENERATE, FLAG_UNORIENTED};
use crate::pipeline::Progress;
use crate::store::{Column, PointStore, TileEntry};
use rayon::prelude::*;
use std::cmp::Reverse;
use std::collections::HashMap;
use std::sync::Mutex;

/// Memory per point of the in-memory pass: the union-find's parent (4),
/// rank (1) and parity bit, rounded up.
pub const BYTES_PER_POINT: u64 = 6;

#[derive(Clone, Copy, Debug, Default)]
pub struct OrientStats {
    pub components: usize,
    pub unoriented: u64,
}

/// A component's facts while its points are being gathered (over
/// non-degenerate points; ids fit u32, see `store::build::MAX_POINTS`).
#[derive(Clone, Debug, Default)]
struct Gathered {
    size: u32,
    top: Rank,
    /// The paper's rule at the top point: flip every member's parity by
    /// this to make the top point face +z (when the vote is even).
    top_sign: bool,
    voters: Voters,
}

impl Gathered {
    /// Adds one non-degenerate point: height `z`, input id `id`, normal
    /// z `nz`, parity to the root `parity`.
    fn add(&mut self, column: u16, z: f32, id: u32, nz: f32, parity: bool, isolated: bool) {
        let rank = Rank::new(z, id, isolated);
        if self.size == 0 || rank > self.top {
            (self.top, self.top_sign) = (rank, parity ^ (nz < 0.0));
        }
        if !isolated {
            self.voters.offer(Voter::new(column, z, id, nz, parity));
        }
        self.size += 1;
    }

    /// Joins the facts of a disjoint set of the same component.
    fn absorb(&mut self, o: &Gathered) {
        if o.size == 0 {
            return;
        }
        if self.size == 0 || o.top > self.top {
            (self.top, self.top_sign) = (o.top, o.top_sign);
        }
        self.voters.merge(&o.voters);
        self.size += o.size;
    }

    /// The facts of the whole component, once every point is in.
    fn settle(&self) -> Component {
        Component {
            size: self.size,
            top: self.top,
            sign: self.voters.verdict().unwrap_or(self.top_sign),
        }
    }
}

/// A component's facts.
#[derive(Clone, Copy, Debug, Default)]
struct Component {
    size: u32,
    /// Its highest point that is not isolated (the island rule's key).
    top: Rank,
    /// Flip every member's parity by this to make the component face out.
    sign: bool,
}

/// The store columns the orientation reads and writes.
#[derive(Clone, Copy)]
pub(crate) struct Columns<'a> {
    pub normals: &'a Column,
    pub flags: &'a Column,
    pub isolated: &'a Isolated,
    /// The sign vote's columns.
    pub grid: ColumnGrid,
    /// Whether the runs tie anchors to the sky ([`anchors`]): its slot is
    /// one past the last point, and its component faces as the sky says.
    pub sky: bool,
}

pub fn orient_by_forest(
    store: &PointStore,
    runs: EdgeRuns,
    columns: Columns,
    progress: &dyn Progress,
) -> Result<OrientStats, NormalsError> {
    let mut uf = ParityUnionFind::new(store.len() as usize + usize::from(columns.sky));
    runs.union_all(&mut uf, "orient: spanning tree", progress)?;
    progress.begin("orient: components", store.len());
    let comps = uf.into_components();
    let mut facts = components(store, &comps, columns, progress)?;
    progress.end();
    let (normals, flags) = (columns.normals, columns.flags);
    // The sky's component faces as its anchors do: each anchor's parity to
    // the sky is its own flip, so the component's sign is the sky's parity.
    let sky = columns.sky.then(|| comps.get(store.len() as u32));
    if let Some((label, parity)) = sky {
        facts[label as usize].sign = parity;
    }
    let reached = island_rule(&facts, sky.map(|s| s.0));
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
    columns: Columns,
    progress: &dyn Progress,
) -> Result<Vec<Component>, NormalsError> {
    // Each tile's share is absorbed as it comes (absorbing is order-free),
    // so the voters of every tile are never held at once.
    let facts = Mutex::new(vec![Gathered::default(); comps.count()]);
    store.tiles().par_iter().try_for_each(|t| {
        let part = tile_components(store, t, columns, |i| {
            let (label, parity) = comps.get(i as u32);
            (u64::from(label), parity)
        })?;
        let mut facts = facts.lock().unwrap_or_else(|e| e.into_inner());
        for (label, c) in &part {
            facts[*label as usize].absorb(c);
        }
        progress.advance(t.count);
        Ok::<_, NormalsError>(())
    })?;
    let facts = facts.into_inner().unwrap_or_else(|e| e.into_inner());
    Ok(facts.iter().map(Gathered::settle).collect())
}

/// One tile's share of the component facts, one entry per label it meets,
/// in order of first appearance; `label_of(store index)` gives a point's
/// component label and parity.
fn tile_components(
    store: &PointStore,
    t: &TileEntry,
    columns: Columns,
    label_of: impl Fn(u64) -> (u64, bool),
) -> Result<Vec<(u64, Gathered)>, NormalsError> {
    let (mut xyz, mut ids, mut nrm, mut flg) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let mut isolated = Vec::new();
    store.read_coords(t.start, t.count, &mut xyz)?;
    store.read_indices(t.start, t.count, &mut ids)?;
    columns.normals.read_f32(t.start, t.count, &mut nrm)?;
    columns.flags.read_u8(t.start, t.count, &mut flg)?;
    columns.isolated.read_tile(t, &mut isolated)?;
    let mut part: Vec<(u64, Gathered)> = Vec::new();
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
                part.push((label, Gathered::default()));
                part.len() - 1
            }),
        };
        last = Some((label, slot));
        let (z, nz) = (xyz[3 * i + 2], nrm[3 * i + 2]);
        let column = columns.grid.column(xyz[3 * i], xyz[3 * i + 1]);
        part[slot]
            .1
            .add(column, z, id as u32, nz, parity, isolated[i]);
    }
    Ok(part)
}

/// Whether the island rule orients each component (by label) with the
/// rest; the others are islands, signed by their own root rule. The sky's
/// component (`sky`), when there is one, comes first.
fn island_rule(facts: &[Component], sky: Option<u32>) -> Vec<bool> {
    let total: u64 = facts.iter().map(|c| u64::from(c.size)).sum();
    let mut order: Vec<u32> = (0..facts.len() as u32)
        .filter(|&l| facts[l as usize].size > 0 || Some(l) == sky)
        .collect();
    // The component of the highest point first, then by size.
    let first = sky.or_else(|| order.iter().copied().max_by_key(|&l| facts[l as usize].top));
    order.sort_by_key(|&l| {
        let c = &facts[l as usize];
        (Some(l) != first, Reverse(c.size), c.top.id())
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
    /// is not tied to the rest), but signed by its own vote, so a
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_isolated_point_neither_votes_nor_tops_its_component() {
        // Parities all 0: a point "says" flip when its normal faces down.
        let mut c = Gathered::default();
        c.add(0, 1.0, 7, 0.3, false, false);
        c.add(0, 0.9, 8, 0.2, false, false);
        // Far above, facing down firmly: it would win the top and the vote.
        c.add(0, 50.0, 9, -1.0, false, true);
        let settled = c.settle();
        assert_eq!(settled.top.id(), 7);
        assert!(!settled.sign, "two voters face up: keep");
        assert_eq!(settled.size, 3);
        // Merged in the other order, the same facts.
        let (mut a, mut b) = (Gathered::default(), Gathered::default());
        a.add(0, 50.0, 9, -1.0, false, true);
        b.add(0, 0.9, 8, 0.2, false, false);
        b.add(0, 1.0, 7, 0.3, false, false);
        a.absorb(&b);
        let again = a.settle();
        assert_eq!((again.top, again.sign, again.size), (settled.top, false, 3));
    }

    #[test]
    fn a_component_of_isolated_points_falls_back_to_its_top() {
        let mut c = Gathered::default();
        c.add(0, 2.0, 3, -0.5, true, true);
        c.add(0, 1.0, 4, 0.9, false, true);
        // No voter: the paper's rule at the highest point. It faces down
        // but has parity 1, so its own flip already turns it up: keep.
        let settled = c.settle();
        assert_eq!(settled.top.id(), 3);
        assert!(!settled.sign);
    }
}
