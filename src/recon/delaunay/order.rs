//! Insertion order of the triangulation: duplicates removed, then a biased
//! randomized insertion order (BRIO, Amenta, Choi & Rote 2003) whose rounds
//! are each sorted along a 3-D Hilbert curve, so consecutive points are near
//! each other (short walks, warm caches) while the rounds keep the expected
//! cavity sizes of a random order.
//!
//! The randomness is a hash of the point's rank (input id), so the order,
//! like the triangulation, depends only on the points and their ids.

use glam::DVec3;

/// Bits per axis of the Hilbert grid (3 x 19 = 57 bits of key).
const HILBERT_BITS: u32 = 19;

/// Points in the first BRIO round at least; smaller inputs are one round.
const FIRST_ROUND: usize = 64;

/// The insertion order and the duplicates left out of it.
#[derive(Debug, Default)]
pub struct InsertionOrder {
    /// Indices of distinct points, in insertion order.
    pub order: Vec<u32>,
    /// `(duplicate, kept)`: a point equal to a kept one of smaller rank.
    pub duplicates: Vec<(u32, u32)>,
}

/// Orders `points` for insertion; `ranks` are their tie keys (input ids).
pub fn insertion_order(points: &[DVec3], ranks: &[u64]) -> InsertionOrder {
    let mut keyed = hilbert_sorted(points);
    let duplicates = remove_duplicates(&mut keyed, points, ranks);
    let rounds = brio_rounds(keyed.len());
    // Counting sort by round keeps the Hilbert order inside each round.
    let round_of = |i: u32| rounds - 1 - (mix(ranks[i as usize]).trailing_zeros()).min(rounds - 1);
    let mut counts = vec![0usize; rounds as usize + 1];
    for &(_, i) in &keyed {
        counts[round_of(i) as usize + 1] += 1;
    }
    for r in 1..counts.len() {
        counts[r] += counts[r - 1];
    }
    let mut order = vec![0u32; keyed.len()];
    for &(_, i) in &keyed {
        let slot = &mut counts[round_of(i) as usize];
        order[*slot] = i;
        *slot += 1;
    }
    InsertionOrder { order, duplicates }
}

/// Rounds so that the first holds about [`FIRST_ROUND`] points: a point is
/// in round `rounds - 1 - k` with probability 2^-(k+1).
fn brio_rounds(n: usize) -> u32 {
    let mut rounds = 1;
    while n >> rounds >= FIRST_ROUND && rounds < 32 {
        rounds += 1;
    }
    rounds
}

/// SplitMix64's finaliser: a well-mixed hash of a rank.
fn mix(x: u64) -> u64 {
    let mut z = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// `(hilbert key, index)` of every point, sorted.
fn hilbert_sorted(points: &[DVec3]) -> Vec<(u64, u32)> {
    let mut lo = DVec3::splat(f64::INFINITY);
    let mut hi = DVec3::splat(f64::NEG_INFINITY);
    for p in points {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    let extent = (hi - lo).max_element();
    let cells = (1u64 << HILBERT_BITS) as f64;
    let scale = if extent > 0.0 {
        (cells - 1.0) / extent
    } else {
        0.0
    };
    let mut keyed: Vec<(u64, u32)> = points
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let g = ((*p - lo) * scale).to_array().map(|c| c as u32);
            (hilbert_key(g), i as u32)
        })
        .collect();
    keyed.sort_unstable();
    keyed
}

/// Drops points equal to another of smaller rank. Equal points have equal
/// keys, so they sit in the same run of the sorted keys.
fn remove_duplicates(
    keyed: &mut Vec<(u64, u32)>,
    points: &[DVec3],
    ranks: &[u64],
) -> Vec<(u32, u32)> {
    let mut duplicates = Vec::new();
    let mut out = 0;
    let mut run = 0;
    while run < keyed.len() {
        let mut end = run + 1;
        while end < keyed.len() && keyed[end].0 == keyed[run].0 {
            end += 1;
        }
        if end - run > 1 {
            // Coordinates, then rank: each point's first equal is the kept one.
            keyed[run..end].sort_unstable_by(|a, b| {
                let (pa, pb) = (points[a.1 as usize], points[b.1 as usize]);
                pa.to_array()
                    .partial_cmp(&pb.to_array())
                    .unwrap_or(std::cmp::Ordering::Equal)
                    .then(ranks[a.1 as usize].cmp(&ranks[b.1 as usize]))
            });
        }
        let mut kept = keyed[run].1;
        for k in run..end {
            let i = keyed[k].1;
            if k > run && points[i as usize] == points[kept as usize] {
                duplicates.push((i, kept));
                continue;
            }
            kept = i;
            keyed[out] = keyed[k];
            out += 1;
        }
        run = end;
    }
    keyed.truncate(out);
    duplicates
}

/// Index of a grid cell along the 3-D Hilbert curve (Skilling, "Programming
/// the Hilbert curve", AIP Conf. Proc. 707, 2004: axes to transposed index,
/// then the bits interleaved).
pub fn hilbert_key(mut x: [u32; 3]) -> u64 {
    let m = 1u32 << (HILBERT_BITS - 1);
    let mut q = m;
    while q > 1 {
        let p = q - 1;
        for i in 0..3 {
            if x[i] & q != 0 {
                x[0] ^= p;
            } else {
                let t = (x[0] ^ x[i]) & p;
                x[0] ^= t;
                x[i] ^= t;
            }
        }
        q >>= 1;
    }
    x[1] ^= x[0];
    x[2] ^= x[1];
    let mut t = 0;
    q = m;
    while q > 1 {
        if x[2] & q != 0 {
            t ^= q - 1;
        }
        q >>= 1;
    }
    for c in &mut x {
        *c ^= t;
    }
    let mut key = 0u64;
    for b in (0..HILBERT_BITS).rev() {
        for c in x {
            key = (key << 1) | ((c >> b) & 1) as u64;
        }
    }
    key
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hilbert_steps_are_unit_moves() {
        // Along the curve, consecutive cells of a 2^19 grid's corner block
        // are face neighbours: check on the first 4096 keys by inverting
        // through a brute-force table of an 16^3 sub-block.
        let mut cells: Vec<(u64, [u32; 3])> = Vec::new();
        for x in 0..16 {
            for y in 0..16 {
                for z in 0..16 {
                    cells.push((hilbert_key([x, y, z]), [x, y, z]));
                }
            }
        }
        cells.sort_unstable();
        // The 16^3 corner block is one sub-cube of the curve: keys 0..4096.
        assert_eq!(cells.last().map(|c| c.0), Some(4095));
        for w in cells.windows(2) {
            let d: u32 = (0..3).map(|a| w[0].1[a].abs_diff(w[1].1[a])).sum();
            assert_eq!(d, 1, "{:?} -> {:?}", w[0], w[1]);
        }
    }

    #[test]
    fn duplicates_keep_the_smallest_rank() {
        let p = DVec3::new(1.0, 2.0, 3.0);
        let points = vec![p, DVec3::ZERO, p, p, DVec3::ONE];
        let ranks = vec![7, 1, 3, 9, 2];
        let o = insertion_order(&points, &ranks);
        let mut order = o.order.clone();
        order.sort_unstable();
        assert_eq!(order, vec![1, 2, 4]);
        let mut d = o.duplicates.clone();
        d.sort_unstable();
        assert_eq!(d, vec![(0, 2), (3, 2)]);
    }
}
