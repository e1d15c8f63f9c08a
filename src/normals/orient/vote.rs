//! The sign of a component: which way its normals face.
//!
//! Paper 1 (section 2.4, step 1) roots the tree at the point of largest z
//! and turns its normal to face +z. Deviation: the sign is a vote of the
//! component's [`VOTERS`] highest points, isolated outliers left out
//! ([`super::isolated`]), each voting for the sign that turns its own
//! normal to face +z, weighted by `|n.z|`. One stray point above a closed
//! surface (a bird, a flying pixel) was otherwise the root, its plane
//! fitted to surface points below it and its normal noise, and it turned
//! the whole surface inside out about every second time. The highest
//! points of a closed surface surround its top, where the outward normals
//! face up; an open sheet's (terrain: roofs, tree tops) face up too. Votes
//! come only from the top: an open sheet's lowest points and side
//! extremes face up as well, so votes from -z or the sides would flip it.
//! A vote that comes out even (no voter, or all level) falls back to the
//! paper's rule at the top point.
//!
//! Everything here is order-free, so tiles merge in any grouping to the
//! same sign: sizes are sums, the top is a maximum under a total order
//! (input ids break ties), the voters are the [`VOTERS`] largest under it,
//! and the tally is an integer sum of quantised weights.

use std::cmp::Reverse;

/// How many of a component's highest points vote on its sign. Enough
/// that a few stray points among them cannot outvote the surface; few
/// enough that they lie on the top cap of an object the size of a few
/// hundred points.
pub(crate) const VOTERS: usize = 64;

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
    z: u32,
    id: u32,
    /// `+w` for "flip the component's parity", `-w` for "keep it", with
    /// `w` its quantised `|n.z|`.
    vote: i32,
}

impl Voter {
    /// A point at height `z` with input id `id`, whose normal's z is `nz`
    /// once its parity to the component's root is `parity`.
    pub(super) fn new(z: f32, id: u32, nz: f32, parity: bool) -> Self {
        let w = (nz.abs().min(1.0) * WEIGHT_UNIT).round() as i32;
        Voter {
            z: ordered_bits(z),
            id,
            vote: if parity ^ (nz < 0.0) { w } else { -w },
        }
    }

    fn key(&self) -> (u32, Reverse<u32>) {
        (self.z, Reverse(self.id))
    }
}

/// A component's [`VOTERS`] highest voters so far, highest first. The
/// in-memory pass keeps one per component, and a cloud can have millions
/// (islands, and every degenerate point is a component of its own), so
/// the `Vec` is boxed: 8 bytes for a component without voters, not 24.
#[derive(Clone, Debug, Default)]
#[allow(clippy::box_collection)]
pub(super) struct Voters(Option<Box<Vec<Voter>>>);

impl Voters {
    /// Adds `v`, keeping the [`VOTERS`] highest.
    pub(super) fn offer(&mut self, v: Voter) {
        let best = self.0.get_or_insert_with(Box::default);
        if best.len() == VOTERS && best.last().is_some_and(|l| l.key() >= v.key()) {
            return;
        }
        let at = best.partition_point(|b| b.key() > v.key());
        best.insert(at, v);
        best.truncate(VOTERS);
    }

    /// Joins the voters of a disjoint set of the same component.
    pub(super) fn merge(&mut self, o: &Voters) {
        let Some(theirs) = o.0.as_deref() else {
            return;
        };
        let Some(ours) = self.0.as_deref_mut() else {
            self.0 = o.0.clone();
            return;
        };
        let mut merged = Vec::with_capacity(VOTERS.min(ours.len() + theirs.len()));
        let (mut a, mut b) = (ours.iter().peekable(), theirs.iter().peekable());
        while merged.len() < VOTERS {
            let next = match (a.peek(), b.peek()) {
                (Some(x), Some(y)) if x.key() >= y.key() => a.next(),
                (Some(_), Some(_)) | (None, Some(_)) => b.next(),
                (Some(_), None) => a.next(),
                (None, None) => break,
            };
            merged.extend(next.copied());
        }
        *ours = merged;
    }

    /// The sign the voters give: `Some(true)` to flip the component's
    /// parity, `Some(false)` to keep it, `None` when the vote is even.
    pub(super) fn verdict(&self) -> Option<bool> {
        let tally: i64 = self
            .0
            .iter()
            .flat_map(|b| b.iter())
            .map(|v| i64::from(v.vote))
            .sum();
        (tally != 0).then_some(tally > 0)
    }

    #[cfg(test)]
    fn ids(&self) -> Vec<u32> {
        self.0.iter().flat_map(|b| b.iter()).map(|v| v.id).collect()
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
    fn voters_keep_the_highest_in_any_grouping() {
        let mut rng = crate::synth::Rng::new(3);
        let all: Vec<Voter> = (0..500)
            .map(|i| {
                let z = rng.range(-1.0, 1.0) as f32;
                Voter::new(z, i, rng.range(-1.0, 1.0) as f32, rng.below(2) == 1)
            })
            .collect();
        let mut one = Voters::default();
        all.iter().for_each(|v| one.offer(*v));
        let mut expect = all.clone();
        expect.sort_by_key(|v| Reverse(v.key()));
        let top: Vec<u32> = expect[..VOTERS].iter().map(|v| v.id).collect();
        assert_eq!(one.ids(), top);
        // Split in uneven parts, offered in reverse, merged either way.
        for cut in [0, 7, 250, 499] {
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
    fn a_few_wrong_voters_are_outvoted_and_an_even_vote_has_no_verdict() {
        let mut v = Voters::default();
        assert_eq!(v.verdict(), None);
        // The top point faces down with parity 0; the 63 below face up.
        v.offer(Voter::new(10.0, 0, -0.9, false));
        (1..VOTERS as u32).for_each(|i| v.offer(Voter::new(1.0 - i as f32 * 1e-3, i, 0.8, false)));
        assert_eq!(v.verdict(), Some(false));
        // The same with every parity flipped: the component flips.
        let mut w = Voters::default();
        w.offer(Voter::new(10.0, 0, -0.9, true));
        (1..VOTERS as u32).for_each(|i| w.offer(Voter::new(1.0 - i as f32 * 1e-3, i, 0.8, true)));
        assert_eq!(w.verdict(), Some(true));
        let mut level = Voters::default();
        level.offer(Voter::new(1.0, 1, 0.0, false));
        assert_eq!(level.verdict(), None);
    }
}
