//! A tile's forest packed for the scratch disk: about 11 bytes an edge
//! where a fixed record takes 24, for the runs the external orientation
//! reads back one tile at a time ([`super::runs::Layout::Packed`]).
//!
//! A run is sorted by [`Edge::key`], so its costs only grow: each edge
//! stores the growth of its cost's bits (the flip in the low bit), its
//! first end's slot from the tile's first store index and its second end's
//! from the first's, as LEB128 varints (zigzag for signed steps). An end's
//! input id is not stored when it is the store's own id of that slot,
//! which the reader has for the tile's core (`index.u32`); ends outside
//! the core (margin points, the sky) and any end whose id differs carry
//! theirs. What is read back is the same edges, bit for bit.

use super::forest::Edge;
use std::ops::Range;

/// The ids of a tile's core: `ids[i]` is the input id of store index
/// `range.start + i`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct CoreIds<'a> {
    pub range: &'a Range<u32>,
    pub ids: &'a [u64],
}

impl CoreIds<'_> {
    /// The id the store gives `slot`, when `slot` lies in the core.
    fn of(&self, slot: u32) -> Option<u32> {
        let local = slot.wrapping_sub(self.range.start);
        if local < self.range.end.wrapping_sub(self.range.start) {
            self.ids.get(local as usize).map(|&id| id as u32)
        } else {
            None
        }
    }
}

/// Cost bits without the sign: steps between them are taken modulo 2^63.
const COST_BITS: u64 = (1 << 63) - 1;

/// Appends `edges` packed to `out`.
pub(crate) fn pack(edges: &[Edge], core: CoreIds, out: &mut Vec<u8>) {
    let mut previous = 0u64;
    for e in edges {
        let bits = e.w.abs().to_bits();
        put(
            out,
            (bits.wrapping_sub(previous) & COST_BITS) << 1 | u64::from(e.flips()),
        );
        previous = bits;
        let ids = [e.a, e.b];
        for (k, base) in [core.range.start, e.slots[0]].into_iter().enumerate() {
            let slot = e.slots[k];
            let step = zigzag(i64::from(slot) - i64::from(base));
            let explicit = core.of(slot) != Some(ids[k]);
            put(out, step << 1 | u64::from(explicit));
            if explicit {
                put(out, u64::from(ids[k]));
            }
        }
    }
}

/// The `n` edges packed in `bytes`, or the first edge that cannot be read.
pub(crate) fn unpack(bytes: &[u8], n: usize, core: CoreIds) -> Result<Vec<Edge>, usize> {
    let mut edges = Vec::with_capacity(n);
    let mut at = 0usize;
    let mut previous = 0u64;
    for i in 0..n {
        let mut next = || take(bytes, &mut at).ok_or(i);
        let head = next()?;
        let bits = (previous.wrapping_add(head >> 1)) & COST_BITS;
        previous = bits;
        let mut slots = [0u32; 2];
        let mut ids = [0u32; 2];
        for k in 0..2 {
            let base = if k == 0 { core.range.start } else { slots[0] };
            let code = next()?;
            let slot = i64::from(base) + unzigzag(code >> 1);
            slots[k] = u32::try_from(slot).map_err(|_| i)?;
            ids[k] = match (code & 1 == 1, core.of(slots[k])) {
                (false, Some(id)) => id,
                (false, None) => return Err(i),
                (true, _) => u32::try_from(next()?).map_err(|_| i)?,
            };
        }
        edges.push(Edge {
            w: f64::from_bits(bits | (head & 1) << 63),
            a: ids[0],
            b: ids[1],
            slots,
        });
    }
    if at == bytes.len() {
        Ok(edges)
    } else {
        Err(n)
    }
}

fn zigzag(v: i64) -> u64 {
    ((v << 1) ^ (v >> 63)) as u64
}

fn unzigzag(v: u64) -> i64 {
    (v >> 1) as i64 ^ -((v & 1) as i64)
}

/// LEB128: seven bits a byte, low first, the high bit set on all but the
/// last.
fn put(out: &mut Vec<u8>, mut v: u64) {
    while v >= 0x80 {
        out.push(v as u8 | 0x80);
        v >>= 7;
    }
    out.push(v as u8);
}

fn take(bytes: &[u8], at: &mut usize) -> Option<u64> {
    let mut v = 0u64;
    for shift in (0..64).step_by(7) {
        let b = *bytes.get(*at)?;
        *at += 1;
        v |= u64::from(b & 0x7f).checked_shl(shift)?;
        if b & 0x80 == 0 {
            return Some(v);
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    /// A sorted forest-like run over core `100..300` with ends outside it
    /// (and the sky, slot 1000, id `u32::MAX`), costs of every size.
    fn run(seed: u64) -> (Vec<Edge>, Vec<u64>) {
        let mut rng = Rng::new(seed);
        let ids: Vec<u64> = (0..200).map(|_| rng.below(1 << 32)).collect();
        let id = |s: u32| match s {
            100..300 => ids[(s - 100) as usize] as u32,
            1000 => u32::MAX,
            s => s * 7 + 3,
        };
        let mut edges: Vec<Edge> = (0..500)
            .map(|_| {
                let x = 100 + rng.below(200) as u32;
                let y = match rng.below(10) {
                    0 => 1000,
                    1 => rng.below(100) as u32,
                    _ => 100 + rng.below(200) as u32,
                };
                let cost = match rng.below(4) {
                    0 => 0.0,
                    1 => 1e-300 * rng.uniform(),
                    _ => rng.uniform(),
                };
                let dot = if rng.below(2) == 0 { -1.0 } else { 1.0 };
                Edge::between([id(x), x], [id(y), y], cost, dot)
            })
            .collect();
        edges.sort_unstable_by_key(Edge::key);
        (edges, ids)
    }

    const CORE: Range<u32> = 100..300;

    /// The test runs' core, with `ids` as its ids, and `edges` packed
    /// against it.
    fn packed<'a>(edges: &[Edge], ids: &'a [u64]) -> (CoreIds<'a>, Vec<u8>) {
        let core = CoreIds { range: &CORE, ids };
        let mut bytes = Vec::new();
        pack(edges, core, &mut bytes);
        (core, bytes)
    }

    fn same(a: &[Edge], b: &[Edge]) -> bool {
        a.len() == b.len()
            && a.iter().zip(b).all(|(x, y)| {
                (x.w.to_bits(), x.a, x.b, x.slots) == (y.w.to_bits(), y.a, y.b, y.slots)
            })
    }

    #[test]
    fn runs_come_back_bit_for_bit_and_smaller() {
        for seed in 0..20 {
            let (edges, ids) = run(seed);
            let (core, bytes) = packed(&edges, &ids);
            assert!(
                bytes.len() < edges.len() * 16,
                "seed {seed}: {}",
                bytes.len()
            );
            assert!(same(&unpack(&bytes, edges.len(), core).unwrap(), &edges));
            // Without the core's ids every end carries its own.
            let (none, full) = packed(&edges, &[]);
            assert!(full.len() > bytes.len());
            assert!(same(&unpack(&full, edges.len(), none).unwrap(), &edges));
        }
    }

    #[test]
    fn unsorted_costs_and_wrong_ids_still_come_back() {
        let (mut edges, ids) = run(7);
        edges.reverse();
        edges[3].a ^= 1;
        let (core, bytes) = packed(&edges, &ids);
        assert!(same(&unpack(&bytes, edges.len(), core).unwrap(), &edges));
    }

    #[test]
    fn a_cut_or_padded_run_is_refused() {
        let (edges, ids) = run(3);
        let (core, bytes) = packed(&edges, &ids);
        let n = edges.len();
        assert!(unpack(&bytes[..bytes.len() - 1], n, core).is_err());
        assert!(unpack(&bytes, n - 1, core).is_err());
        let mut long = bytes.clone();
        long.push(0);
        assert!(unpack(&long, n, core).is_err());
        assert!(unpack(&[0xff; 11], 1, core).is_err());
    }
}
