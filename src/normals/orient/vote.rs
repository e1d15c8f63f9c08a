//! The sign of a component: which way its normals face.
//!
//! Paper 1 (section 2.4, step 1) roots the tree at the point of largest z
//! and turns its normal to face +z. Deviation: the sign is a vote, isolated
//! outliers left out ([`super::isolated`]), each voter voting for the sign
//! that turns its own normal to face +z, weighted by `|n.z|`. The voters
//! are the [`PER_COLUMN`] highest points of the component in each column
//! of a [`COLUMNS`] x [`COLUMNS`] grid over the cloud's horizontal bounds
//! ([`ColumnGrid`]). One stray point above a closed surface (a bird, a
//! flying pixel) was once the root, its plane fitted to surface points
//! below it and its normal noise, and it turned the whole surface inside
//! out about every second time; the 64 highest points then voted, which
//! a tree crown holds alone in a scene of ground and trees, and the
//! crown's normals are noise too: a synthetic plot of ground and three
//! trees came out with its ground facing down for 4 seeds of 12
//! (`tests/orient_evidence.rs`). Every column's top now has a say, so the
//! ground outvotes a crown. The highest point of a vertical line through
//! a closed surface faces up (outward), and so does an open sheet's
//! (terrain: roofs, tree tops, ground); votes come only from the top of
//! each column: an open sheet's lowest points and sides face up as well,
//! so votes from -z or the sides would flip it. A vote that comes out
//! even (no voter, or all level) falls back to the paper's rule at the
//! top point.
//!
//! Everything here is order-free, so tiles merge in any grouping to the
//! same sign: sizes are sums, the top is a maximum under a total order
//! (input ids break ties), the voters are the [`PER_COLUMN`] largest under
//! it per column (of a grid the input bounds fix), and the tally is an
//! integer sum of quantised weights.

use std::cmp::Reverse;

/// How many of a component's highest points in each column vote on its
/// sign: few enough that they lie at the column's top.
pub(crate) const PER_COLUMN: usize = 2;

/// Columns of the voting grid along x and along y: enough that an object
/// in an eighth of the bounds' width (a stray point far to its side
/// stretches them) still has 64 columns, up to 128 voters.
pub(crate) const COLUMNS: u32 = 64;

/// The voting grid: [`COLUMNS`] x [`COLUMNS`] columns over the horizontal
/// bounds of the stored (relative) coordinates, which every tiling shares.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ColumnGrid {
    min: [f32; 2],
    inv: [f32; 2],
}

impl ColumnGrid {
    /// The grid over `lo..hi` (x and y).
    pub(crate) fn new(lo: [f64; 2], hi: [f64; 2]) -> Self {
        let inv = |a: usize| {
            let e = hi[a] - lo[a];
            if e > 0.0 && e.is_finite() {
                (f64::from(COLUMNS) / e) as f32
            } else {
                0.0
            }
        };
        ColumnGrid {
            min: [lo[0] as f32, lo[1] as f32],
            inv: [inv(0), inv(1)],
        }
    }

    /// The column of a point at (x, y).
    pub(crate) fn column(&self, x: f32, y: f32) -> u16 {
        let c = |v: f32, a: usize| {
            let f = (v - self.min[a]) * self.inv[a];
            (f.max(0.0) as u32).min(COLUMNS - 1)
        };
        (c(x, 0) * COLUMNS + c(y, 1)) as u16
    }
}

/// Fixed-point units of `|n.z|` in a vote: an integer tally is the same
/// whatever order the votes are added in.
const WEIGHT_UNIT: f32 = 65_536.0;

/// Where a point ranks as a component's top: points that are not isolated
/// before isolated ones, then by height, then by smaller input id. A total
/// order over values every tiling gives alike.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub(super) struct Rank {
    settled: bool,
    z: u32,
    id: Reverse<u32>,
}

impl Rank {
    pub(super) fn new(z: f32, id: u32, isolated: bool) -> Self {
        Rank {
            settled: !isolated,
            z: ordered_bits(z),
            id: Reverse(id),
        }
    }

    /// The point's input id.
    pub(super) fn id(&self) -> u32 {
        self.id.0
    }
}

impl Default for Rank {
    /// Below every point's rank.
    fn default() -> Self {
        Rank {
            settled: false,
            z: 0,
            id: Reverse(u32::MAX),
        }
    }
}

/// `z`'s bits, mapped so that integer order is `f32::total_cmp`'s order.
fn ordered_bits(z: f32) -> u32 {
    let b = z.to_bits();
    if b >> 31 == 1 {
        !b
    } else {
        b | 1 << 31
    }
}

/// One point's say on its component's sign.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Voter {
    column: u16,
    z: u32,
    id: u32,
    /// `+w` for "flip the component's parity", `-w` for "keep it", with
    /// `w` its quantised `|n.z|`.
    vote: i32,
}

impl Voter {
    /// A point at height `z` with input id `id`, whose normal's z is `nz`
    /// once its parity to the component's root is `parity`.
    pub(super) fn new(column: u16, z: f32, id: u32, nz: f32, parity: bool) -> Self {
        let w = (nz.abs().min(1.0) * WEIGHT_UNIT).round() as i32;
        Voter {
            column,
            z: ordered_bits(z),
            id,
            vote: if parity ^ (nz < 0.0) { w } else { -w },
        }
    }

    fn key(&self) -> (u32, Reverse<u32>) {
        (self.z, Reverse(self.id))
    }

    /// Column first, then highest first: the order of a compacted list.
    fn order(&self) -> (u16, Reverse<(u32, Reverse<u32>)>) {
        (self.column, Reverse(self.key()))
    }
}

/// A component's voters so far: the [`PER_COLUMN`] highest per column
/// once compacted. The in-memory pass keeps one per component, and a cloud
/// can have millions (islands, and every degenerate point is a component
/// of its own), so the list is boxed: 8 bytes for a component without
/// voters.
#[derive(Clone, Debug, Default)]
pub(super) struct Voters(Option<Box<Pending>>);

/// Voters offered since the last compaction sit unsorted past `compacted`.
#[derive(Clone, Debug, Default)]
pub(super) struct Pending {
    list: Vec<Voter>,
    compacted: usize,
}

impl Pending {
    /// Sorts by column, highest first, and keeps [`PER_COLUMN`] a column:
    /// the same list whatever order the voters came in.
    fn compact(&mut self) {
        if self.compacted == self.list.len() {
            return;
        }
        self.list.sort_unstable_by_key(Voter::order);
        let mut kept = 0;
        for i in 0..self.list.len() {
            let v = self.list[i];
            let same = kept >= PER_COLUMN && self.list[kept - PER_COLUMN].column == v.column;
            if !same {
                self.list[kept] = v;
                kept += 1;
            }
        }
        self.list.truncate(kept);
        self.compacted = kept;
    }
}

impl Voters {
    /// Adds `v`; the list is compacted once the unsorted part is as long
    /// as the compacted one (and at least 64), so each offer costs a
    /// logarithm amortised.
    pub(super) fn offer(&mut self, v: Voter) {
        let p = self.0.get_or_insert_with(Box::default);
        p.list.push(v);
        if p.list.len() >= 2 * p.compacted.max(32) {
            p.compact();
        }
    }

    /// Joins the voters of a disjoint set of the same component.
    pub(super) fn merge(&mut self, o: &Voters) {
        let Some(theirs) = o.0.as_deref() else {
            return;
        };
        let ours = self.0.get_or_insert_with(Box::default);
        ours.list.extend_from_slice(&theirs.list);
        ours.compact_fully();
    }

    /// The sign the voters give: `Some(true)` to flip the component's
    /// parity, `Some(false)` to keep it, `None` when the vote is even.
    pub(super) fn verdict(&self) -> Option<bool> {
        let mut p = self.0.as_deref().cloned().unwrap_or_default();
        p.compact_fully();
        let tally: i64 = p.list.iter().map(|v| i64::from(v.vote)).sum();
        (tally != 0).then_some(tally > 0)
    }

    #[cfg(test)]
    fn ids(&self) -> Vec<u32> {
        let mut p = self.0.as_deref().cloned().unwrap_or_default();
        p.compact_fully();
        p.list.iter().map(|v| v.id).collect()
    }
}

impl Pending {
    /// Compacts whatever the state.
    fn compact_fully(&mut self) {
        self.compacted = usize::MAX;
        self.compact();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranks_follow_height_then_smaller_id_and_put_isolated_last() {
        let r = Rank::new;
        assert!(r(1.0, 5, false) > r(0.5, 1, false));
        assert!(r(-0.5, 5, false) > r(-1.0, 1, false));
        assert!(r(1.0, 1, false) > r(1.0, 2, false));
        assert!(r(-1e9, 9, false) > r(1e9, 1, true));
        assert!(r(-f32::MAX, u32::MAX - 1, true) > Rank::default());
    }

    #[test]
    fn columns_cover_the_bounds_and_clamp_outside() {
        let g = ColumnGrid::new([0.0, -10.0], [64.0, 54.0]);
        assert_eq!(g.column(0.0, -10.0), 0);
        assert_eq!(g.column(0.5, -9.5), 0);
        assert_eq!(g.column(1.5, -10.0), COLUMNS as u16);
        assert_eq!(g.column(64.0, 54.0), (COLUMNS * COLUMNS - 1) as u16);
        assert_eq!(g.column(-5.0, 99.0), (COLUMNS - 1) as u16);
        let flat = ColumnGrid::new([1.0, 1.0], [1.0, 1.0]);
        assert_eq!(flat.column(1.0, 1.0), 0);
    }

    #[test]
    fn voters_keep_the_highest_per_column_in_any_grouping() {
        let mut rng = crate::rng::Rng::new(3);
        let all: Vec<Voter> = (0..2000)
            .map(|i| {
                let z = rng.range(-1.0, 1.0) as f32;
                let col = rng.below(40) as u16;
                Voter::new(col, z, i, rng.range(-1.0, 1.0) as f32, rng.below(2) == 1)
            })
            .collect();
        let mut one = Voters::default();
        all.iter().for_each(|v| one.offer(*v));
        let mut expect = all.clone();
        expect.sort_by_key(Voter::order);
        let mut top = Vec::new();
        for c in 0..40u16 {
            let col: Vec<u32> = expect
                .iter()
                .filter(|v| v.column == c)
                .map(|v| v.id)
                .collect();
            top.extend(col.into_iter().take(PER_COLUMN));
        }
        assert_eq!(one.ids(), top);
        // Split in uneven parts, offered in reverse, merged either way.
        for cut in [0, 7, 250, 1999] {
            let (mut a, mut b) = (Voters::default(), Voters::default());
            all[..cut].iter().rev().for_each(|v| a.offer(*v));
            all[cut..].iter().for_each(|v| b.offer(*v));
            let mut ab = a.clone();
            ab.merge(&b);
            b.merge(&a);
            assert_eq!(ab.ids(), top, "cut {cut}");
            assert_eq!(b.ids(), top, "cut {cut}");
            assert_eq!(ab.verdict(), one.verdict());
        }
    }

    #[test]
    fn a_crown_of_noise_is_outvoted_by_the_ground_and_an_even_vote_has_no_verdict() {
        let mut v = Voters::default();
        assert_eq!(v.verdict(), None);
        // A crown in one column, far above, its voters all saying "flip";
        // the ground's columns say "keep". The 64 highest would all be
        // the crown's.
        (0..200u32).for_each(|i| v.offer(Voter::new(7, 30.0 + i as f32, i, -0.9, false)));
        (0..30u32).for_each(|c| {
            v.offer(Voter::new(100 + c as u16, 0.1, 1000 + c, 0.95, false));
        });
        assert_eq!(v.verdict(), Some(false));
        // The same with every parity flipped: the component flips.
        let mut w = Voters::default();
        (0..200u32).for_each(|i| w.offer(Voter::new(7, 30.0 + i as f32, i, -0.9, true)));
        (0..30u32).for_each(|c| w.offer(Voter::new(100 + c as u16, 0.1, 1000 + c, 0.95, true)));
        assert_eq!(w.verdict(), Some(true));
        let mut level = Voters::default();
        level.offer(Voter::new(0, 1.0, 1, 0.0, false));
        assert_eq!(level.verdict(), None);
    }
}
