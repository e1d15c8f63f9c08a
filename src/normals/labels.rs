//! The spanning forest of all tiles solved without per-point state in
//! memory: each tile's forest is contracted to its boundary
//! (`super::contract`), Kruskal runs over the super-edges alone (a few
//! per cent of the points), and each tile then gives its core points a
//! component label and a parity, written to a scratch column of the store.
//! The same tree as Kruskal over every point (paper 1 section 2.4, exact),
//! in memory that grows with the tiles' boundaries, not with the points.
//!
//! Passes, each over the tile forests on disk:
//! 1. boundary: the store indices each tile's forest reaches outside the
//!    tile's core (logged by [`EdgeRuns::push_tile_run`] as the forests
//!    arrived), sorted and deduplicated (`B`, 4 bytes each);
//! 2. contract every tile, writing its super-edges (ends numbered densely:
//!    boundary vertices by rank in `B`, branch points after them) as runs;
//! 3. Kruskal over the merged super-edges with a parity union-find over the
//!    nodes, marking the super-edges it takes;
//! 4. resolve every tile's points: its forest without the heaviest edges
//!    of its rejected super-edges, each tree taking the label and parity
//!    of a boundary vertex it holds (`resolve`); each tile's forest is given
//!    back to the file system once its labels are written
//!    ([`EdgeRuns::release_run`]).
//!
//! A label at or above the point count is `count + ` a node component's
//! dense number (it may span tiles); below, a store index of the one tile
//! that holds the whole component.

use super::components::Components;
use super::contract::{contract, resolve, Contraction, LocalForest};
use super::forest::Edge;
use super::runs::{EdgeRuns, Layout};
use super::unionfind::ParityUnionFind;
use super::NormalsError;
use crate::pipeline::Progress;
use crate::store::{Column, PointStore, StoreError, TileEntry};
use rayon::prelude::*;
use std::ops::Range;

/// Scratch column of the labels: `label | parity << 63` per point, or
/// `label | parity << 31` in 4 bytes when every label is below 2^31
/// (a billion points with room to spare).
pub const LABELS_FILE: &str = ".orient.labels";
/// Scratch file of the super-edge runs.
const SUPERS_FILE: &str = ".orient.supers";
/// Read buffers of the super-edge merge.
const MERGE_BUFFER: usize = 16 << 20;
/// The parity bit of a 4-byte label word.
const NARROW_PARITY: u64 = 1 << 31;
/// Tiles contracted at once (in parallel) before their results are written.
const TILES_AT_ONCE: usize = 8;

/// Per-point component labels and parities of the forest, on disk.
pub struct ForestLabels {
    column: Column,
    /// The column holds 4-byte words (see [`LABELS_FILE`]).
    narrow: bool,
    _cleanup: crate::io::cleanup::Registered,
    points: u64,
    /// Node components: how many, for per-component tables.
    pub node_components: usize,
    /// Label and parity of the virtual root, when extra nodes were given.
    root: Option<(u64, bool)>,
    /// Label and parity of the sky (`orient::anchors`), when the runs
    /// reach the slot one past the last point.
    sky: Option<(u64, bool)>,
}

impl ForestLabels {
    /// Solves the forests in `runs` (one run per tile, in tile order, slots
    /// as store indices). `extra` are store indices that must be nodes,
    /// each joined first, with its parity, to one virtual root (the
    /// six-source pass's sources); their labels are then the root's.
    pub fn solve(
        store: &PointStore,
        runs: &mut EdgeRuns,
        extra: &[(u32, bool)],
        progress: &dyn Progress,
    ) -> Result<Self, NormalsError> {
        runs.flush()?;
        let tiles = store.tiles();
        let sources: Vec<u32> = extra.iter().map(|e| e.0).collect();
        let boundary = runs.outside_slots(&sources)?;
        let dir = store.dir();
        let mut supers = EdgeRuns::create(&dir.join(SUPERS_FILE), Layout::Records)?;
        progress.begin("orient: contract", tiles.len() as u64);
        let branches = write_supers(store, runs, &boundary, &mut supers, progress)?;
        progress.end();
        let nodes = boundary.len() as u64 + branches.last().copied().unwrap_or(0) + 1;
        let root = nodes as u32 - 1;
        // The sky (`orient::anchors`), when the runs tie anchors to it, has
        // the slot one past the last point; with sources it is their root.
        let sky_rank = u32::try_from(store.len())
            .ok()
            .and_then(|s| boundary.binary_search(&s).ok())
            .map(|r| r as u32);
        let joined = Joined {
            root,
            extra,
            sky: sky_rank,
        };
        let (comps, accepted) = kruskal(&mut supers, nodes, &joined, &boundary, progress)?;
        let root = (!extra.is_empty()).then(|| {
            let (l, p) = comps.get(root);
            (store.len() + u64::from(l), p)
        });
        let sky = sky_rank.map(|r| {
            let (l, p) = comps.get(r);
            (store.len() + u64::from(l), p)
        });
        // Labels run below the points plus the node components.
        let narrow = store.len() + comps.count() as u64 <= NARROW_PARITY;
        let labels = ForestLabels {
            _cleanup: crate::io::cleanup::register(&dir.join(LABELS_FILE)),
            column: Column::create(
                &dir.join(LABELS_FILE),
                if narrow { 4 } else { 8 },
                store.len(),
            )?,
            narrow,
            points: store.len(),
            node_components: comps.count(),
            root,
            sky,
        };
        progress.begin("orient: resolve", tiles.len() as u64);
        let solved = Solved {
            boundary: &boundary,
            supers: &supers,
            accepted: &accepted,
            comps: &comps,
            points: store.len(),
        };
        labels.resolve_all(store, runs, &solved, progress)?;
        progress.end();
        Ok(labels)
    }

    /// The points' labels and parities of tile `t` (see the module doc).
    pub fn read_tile(&self, t: &TileEntry, out: &mut Vec<u64>) -> Result<(), StoreError> {
        if !self.narrow {
            return self.column.read_u64(t.start, t.count, out);
        }
        self.column.read_u32_wide(t.start, t.count, out)?;
        for w in out.iter_mut() {
            *w = widen(*w as u32);
        }
        Ok(())
    }

    /// The column's bytes of `labels` (`label | parity << 63` each).
    fn column_bytes(&self, labels: &[u64]) -> Vec<u8> {
        if !self.narrow {
            return labels.iter().flat_map(|l| l.to_le_bytes()).collect();
        }
        labels
            .iter()
            .flat_map(|&l| narrow(l).to_le_bytes())
            .collect()
    }

    /// Whether `label` may span tiles (a node component), and its number.
    pub fn node_component(&self, label: u64) -> Option<usize> {
        label.checked_sub(self.points).map(|l| l as usize)
    }

    /// Label and parity of the virtual root the extra nodes were joined
    /// to (`None` without extra nodes).
    pub fn root(&self) -> Option<(u64, bool)> {
        self.root
    }

    /// Label and parity of the sky the runs tie anchors to (`None` when
    /// they do not reach its slot, one past the last point).
    pub fn sky(&self) -> Option<(u64, bool)> {
        self.sky
    }

    fn resolve_all(
        &self,
        store: &PointStore,
        runs: &EdgeRuns,
        solved: &Solved,
        progress: &dyn Progress,
    ) -> Result<(), NormalsError> {
        let tiles = store.tiles();
        for_tile_batches(
            store,
            runs,
            progress,
            |t, forest, local| {
                let core = boundary_core(solved.boundary, &tiles[t]);
                let rejected = solved.rejected(t)?;
                let labels = resolve(forest, local, &rejected, core, |s| {
                    let (l, p) = solved.comps.get(rank(solved.boundary, s));
                    (solved.points + u64::from(l), p)
                });
                Ok(self.column_bytes(&labels))
            },
            |t, bytes| {
                self.column.write_bytes(tiles[t].start, &bytes)?;
                // Pass 4 is the forests' last read: as the labels grow, the
                // forests shrink, and the scratch peak is not their sum.
                runs.release_run(t)?;
                Ok(())
            },
        )
    }
}

impl Drop for ForestLabels {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(self.column.path());
    }
}

/// What passes 2 and 3 found, for pass 4.
struct Solved<'a> {
    boundary: &'a [u32],
    /// The super-edge runs, one per tile.
    supers: &'a EdgeRuns,
    /// Super-edges Kruskal took, one bit each by position.
    accepted: &'a [u64],
    comps: &'a Components,
    points: u64,
}

impl Solved<'_> {
    /// The `(a, b)` ids of the heaviest edges of tile `t`'s rejected
    /// super-edges, sorted.
    fn rejected(&self, t: usize) -> Result<Vec<(u32, u32)>, NormalsError> {
        let base = self.supers.run_start(t);
        let run = self.supers.read_run(t, &[])?;
        let mut ids: Vec<(u32, u32)> = (0..run.len())
            .filter(|&k| !bit(self.accepted, base + k as u64))
            .map(|k| (run[k].a, run[k].b))
            .collect();
        ids.sort_unstable();
        Ok(ids)
    }
}

/// Dense numbers of `c`'s nodes, in the order of [`Contraction::nodes`]:
/// a boundary vertex by its rank in `boundary`, a branch point by the
/// tile's running count from `first_branch` (after all boundary vertices).
fn dense_nodes(c: &Contraction, boundary: &[u32], first_branch: u64) -> Vec<u32> {
    let mut next = boundary.len() as u64 + first_branch;
    c.nodes()
        .map(|(store, is_branch)| {
            if is_branch {
                next += 1;
                (next - 1) as u32
            } else {
                rank(boundary, store)
            }
        })
        .collect()
}

/// A label word (`label | parity << 63`, the label below 2^31) in 4 bytes.
fn narrow(word: u64) -> u32 {
    (word & (NARROW_PARITY - 1)) as u32 | (word >> 63 << 31) as u32
}

/// The label word of [`narrow`]'s 4 bytes.
fn widen(word: u32) -> u64 {
    let w = u64::from(word);
    (w & (NARROW_PARITY - 1)) | (w & NARROW_PARITY) << 32
}

fn bit(bits: &[u64], i: u64) -> bool {
    bits[(i / 64) as usize] >> (i % 64) & 1 == 1
}

fn rank(boundary: &[u32], s: u32) -> u32 {
    boundary.binary_search(&s).unwrap_or_default() as u32
}

fn core_range(t: &TileEntry) -> Range<u32> {
    t.start as u32..(t.start + t.count) as u32
}

/// The boundary vertices in tile `t`'s core (a slice of the sorted `B`).
fn boundary_core<'a>(boundary: &'a [u32], t: &TileEntry) -> &'a [u32] {
    let range = core_range(t);
    let lo = boundary.partition_point(|&s| s < range.start);
    let hi = boundary.partition_point(|&s| s < range.end);
    &boundary[lo..hi]
}

/// Runs `work` on the tiles' forests in batches (in parallel within one)
/// and hands each result to `done` in tile order.
fn for_tile_batches<R: Send>(
    store: &PointStore,
    runs: &EdgeRuns,
    progress: &dyn Progress,
    work: impl Fn(usize, &[Edge], &LocalForest) -> Result<R, NormalsError> + Sync,
    mut done: impl FnMut(usize, R) -> Result<(), NormalsError>,
) -> Result<(), NormalsError> {
    let tiles = store.tiles();
    let numbers: Vec<usize> = (0..tiles.len()).collect();
    for batch in numbers.chunks(TILES_AT_ONCE) {
        let results: Vec<R> = batch
            .par_iter()
            .map(|&t| {
                let mut ids = Vec::new();
                store.read_indices(tiles[t].start, tiles[t].count, &mut ids)?;
                let forest = runs.read_run(t, &ids)?;
                let range = core_range(&tiles[t]);
                let local = LocalForest::new(&forest, range.start, range.end - range.start);
                work(t, &forest, &local)
            })
            .collect::<Result<_, NormalsError>>()?;
        for (&t, r) in batch.iter().zip(results) {
            done(t, r)?;
            progress.advance(1);
        }
    }
    Ok(())
}

/// Pass 2: every tile's super-edges, ends numbered densely, one run per
/// tile. Returns each tile's first branch number and, last, their total.
fn write_supers(
    store: &PointStore,
    runs: &EdgeRuns,
    boundary: &[u32],
    supers: &mut EdgeRuns,
    progress: &dyn Progress,
) -> Result<Vec<u64>, NormalsError> {
    let tiles = store.tiles();
    let mut branches = vec![0u64];
    let contract_tile = |t: usize, forest: &[Edge], local: &LocalForest| {
        Ok(contract(forest, local, boundary_core(boundary, &tiles[t])))
    };
    for_tile_batches(store, runs, progress, contract_tile, |_, c| {
        let first = *branches.last().unwrap_or(&0);
        let dense = dense_nodes(&c, boundary, first);
        let run: Vec<Edge> = c
            .supers()
            .iter()
            .map(|e| Edge {
                slots: e.slots.map(|v| dense[c.node_position(v)]),
                ..*e
            })
            .collect();
        supers.push_run(&run)?;
        branches.push(first + c.nodes().filter(|n| n.1).count() as u64);
        Ok(())
    })?;
    Ok(branches)
}

/// Pass 3: Kruskal over the super-edges; the extra nodes are joined to the
/// virtual `root` first. Returns the node components and the taken edges.
/// The nodes joined before any super-edge: the extra nodes to the virtual
/// root, and the sky (a boundary node, by rank) to it too when there are
/// extra nodes (one virtual node, as in the in-memory passes).
struct Joined<'a> {
    root: u32,
    extra: &'a [(u32, bool)],
    sky: Option<u32>,
}

fn kruskal(
    supers: &mut EdgeRuns,
    nodes: u64,
    joined: &Joined,
    boundary: &[u32],
    progress: &dyn Progress,
) -> Result<(Components, Vec<u64>), NormalsError> {
    let mut uf = ParityUnionFind::new(nodes as usize);
    for &(s, parity) in joined.extra {
        uf.union(rank(boundary, s), joined.root, parity);
    }
    if let (Some(sky), false) = (joined.sky, joined.extra.is_empty()) {
        uf.union(sky, joined.root, false);
    }
    let mut accepted = vec![0u64; supers.edges().div_ceil(64) as usize];
    progress.begin("orient: spanning tree", supers.edges());
    supers.merge_numbered(MERGE_BUFFER, |at, e| {
        if uf.union(e.slots[0], e.slots[1], e.flips()) {
            accepted[(at / 64) as usize] |= 1 << (at % 64);
        }
        progress.advance(1);
    })?;
    progress.end();
    Ok((uf.into_components(), accepted))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_label_word_survives_four_bytes_up_to_its_limit() {
        for label in [0, 1, 12_345, (1 << 30) + 7, NARROW_PARITY - 1] {
            for parity in [0u64, 1] {
                let word = label | parity << 63;
                assert_eq!(widen(narrow(word)), word, "{label} {parity}");
            }
        }
    }
}
