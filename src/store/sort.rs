//! Per-tile ordering pass of the store build: sorts each tile's points along
//! a Morton (Z-order) curve so nearby points are nearby on disk, counts exact
//! duplicates (adjacent after the sort), and records tile and block bounds.

use super::{Column, StoreError, TileEntry, BLOCK, BLOCKS_FILE, INDEX_FILE, XYZ_FILE};
use crate::progress::Progress;
use rayon::prelude::*;
use std::path::Path;

/// Sorts every tile in place; fills in tile bounds; returns the duplicate count.
pub fn sort_tiles(
    dir: &Path,
    tiles: &mut [TileEntry],
    progress: &dyn Progress,
) -> Result<u64, StoreError> {
    let xyz = Column::open(&dir.join(XYZ_FILE), 12, true)?;
    let index = Column::open(&dir.join(INDEX_FILE), 4, true)?;
    let blocks = Column::open(&dir.join(BLOCKS_FILE), 24, true)?;
    progress.begin("sort tiles", tiles.len() as u64);
    let dups: Result<Vec<u64>, StoreError> = tiles
        .par_iter_mut()
        .map(|t| {
            let d = sort_tile(t, &xyz, &index, &blocks);
            progress.advance(1);
            d
        })
        .collect();
    progress.end();
    Ok(dups?.iter().sum())
}

fn sort_tile(
    t: &mut TileEntry,
    xyz: &Column,
    index: &Column,
    blocks: &Column,
) -> Result<u64, StoreError> {
    if t.count == 0 {
        return Ok(0);
    }
    let mut raw = Vec::new();
    let mut ids = Vec::new();
    xyz.read_f32(t.start, t.count, &mut raw)?;
    index.read_u32_wide(t.start, t.count, &mut ids)?;
    let (lo, hi) = bounds(&raw);
    t.points_min = lo;
    t.points_max = hi;
    let order = morton_order(&raw, &ids, lo, hi);
    let point = |i: usize| [raw[3 * i], raw[3 * i + 1], raw[3 * i + 2]];
    let sorted: Vec<f32> = order.iter().flat_map(|&i| point(i)).collect();
    let duplicates = sorted
        .chunks_exact(3)
        .zip(sorted.chunks_exact(3).skip(1))
        .filter(|(a, b)| a == b)
        .count() as u64;
    let sorted_ids: Vec<u64> = order.iter().map(|&i| ids[i]).collect();
    xyz.write_f32(t.start, &sorted)?;
    index.write_u32_narrow(t.start, &sorted_ids)?;
    let block_bounds: Vec<f32> = sorted
        .chunks(3 * BLOCK as usize)
        .flat_map(|b| {
            let (l, h) = bounds(b);
            [l[0], l[1], l[2], h[0], h[1], h[2]]
        })
        .collect();
    blocks.write_f32(t.first_block, &block_bounds)?;
    Ok(duplicates)
}

/// Positions of the points `raw` (flat x, y, z) in the order (Morton key,
/// coordinate bits, id). Keys and positions are packed in a u128 so the
/// sort compares plain integers; only runs of equal keys (points in one
/// 2^-21 cell: duplicates, mostly) are then ordered by their coordinates
/// and ids, which gives the same total order as sorting by the triple.
fn morton_order(raw: &[f32], ids: &[u64], lo: [f32; 3], hi: [f32; 3]) -> Vec<usize> {
    let mut packed: Vec<u128> = raw
        .chunks_exact(3)
        .enumerate()
        .map(|(i, c)| u128::from(morton([c[0], c[1], c[2]], lo, hi)) << 64 | i as u128)
        .collect();
    packed.sort_unstable();
    let mut order: Vec<usize> = packed.iter().map(|&k| k as u64 as usize).collect();
    let tie = |&i: &usize| {
        (
            [raw[3 * i], raw[3 * i + 1], raw[3 * i + 2]].map(f32::to_bits),
            ids[i],
        )
    };
    let mut s = 0;
    while s < packed.len() {
        let key = packed[s] >> 64;
        let mut e = s + 1;
        while e < packed.len() && packed[e] >> 64 == key {
            e += 1;
        }
        if e - s > 1 {
            order[s..e].sort_unstable_by_key(tie);
        }
        s = e;
    }
    order
}

fn bounds(raw: &[f32]) -> ([f32; 3], [f32; 3]) {
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for c in raw.chunks_exact(3) {
        for a in 0..3 {
            lo[a] = lo[a].min(c[a]);
            hi[a] = hi[a].max(c[a]);
        }
    }
    (lo, hi)
}

/// 63-bit Morton key of `p` quantised to 21 bits per axis within `[lo, hi]`.
fn morton(p: [f32; 3], lo: [f32; 3], hi: [f32; 3]) -> u64 {
    let mut key = 0u64;
    for a in 0..3 {
        let span = (hi[a] - lo[a]) as f64;
        let q = if span > 0.0 {
            (((p[a] - lo[a]) as f64 / span) * ((1u64 << 21) - 1) as f64) as u64
        } else {
            0
        };
        key |= spread3(q) << a;
    }
    key
}

/// Spreads the low 21 bits of `v` to every third bit.
fn spread3(v: u64) -> u64 {
    let mut x = v & 0x1f_ffff;
    x = (x | (x << 32)) & 0x001f_0000_0000_ffff;
    x = (x | (x << 16)) & 0x001f_0000_ff00_00ff;
    x = (x | (x << 8)) & 0x100f_00f0_0f00_f00f;
    x = (x | (x << 4)) & 0x10c3_0c30_c30c_30c3;
    x = (x | (x << 2)) & 0x1249_2492_4924_9249;
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spread_interleaves() {
        assert_eq!(spread3(0b1), 0b1);
        assert_eq!(spread3(0b11), 0b1001);
        assert_eq!(spread3(0b101), 0b1000001);
        assert_eq!(spread3((1 << 21) - 1).count_ones(), 21);
    }

    #[test]
    fn order_is_key_then_coordinates_then_id() {
        let mut rng = crate::rng::Rng::new(9);
        // Few distinct positions, so many points share a Morton cell.
        let pick = |rng: &mut crate::rng::Rng| [0; 3].map(|_| rng.below(5) as f32 * 0.25);
        let pts: Vec<[f32; 3]> = (0..3000).map(|_| pick(&mut rng)).collect();
        let raw: Vec<f32> = pts.iter().flatten().copied().collect();
        let ids: Vec<u64> = (0..pts.len() as u64).map(|i| (i * 7919) % 3001).collect();
        let (lo, hi) = bounds(&raw);
        let mut want: Vec<usize> = (0..pts.len()).collect();
        want.sort_by_key(|&i| (morton(pts[i], lo, hi), pts[i].map(f32::to_bits), ids[i]));
        assert_eq!(morton_order(&raw, &ids, lo, hi), want);
    }

    #[test]
    fn morton_orders_octants() {
        let lo = [0.0; 3];
        let hi = [1.0; 3];
        assert!(morton([0.1, 0.1, 0.1], lo, hi) < morton([0.9, 0.1, 0.1], lo, hi));
        assert!(morton([0.9, 0.1, 0.1], lo, hi) < morton([0.1, 0.9, 0.1], lo, hi));
        assert!(morton([0.9, 0.9, 0.1], lo, hi) < morton([0.1, 0.1, 0.9], lo, hi));
    }
}
