//! Points per occupied histogram cell, for the store build's planning pass.
//!
//! Cells are numbered `x + nx (y + ny z)`; keys are gathered in batches,
//! radix-sorted, run-length counted and merged into a sorted list of
//! (key, count). This replaces a `HashMap<[u32; 3], u64>` whose lookups
//! missed the cache for nearly every point of a scan in scanner (random)
//! order: 137k cells on 1M points, 1.4M on 10M, a table of 8-64 MB. Sorting
//! touches memory in sequence, and the list (12 bytes a cell) is smaller
//! than the table was.
//!
//! The list is bounded: when it would hold more than `cap` cells (a volume
//! scan, or a budget too small for the grid), the grid is coarsened by two
//! along each axis and the list merged down, as often as needed. Occupied
//! cells only grow as points come and only shrink as the grid coarsens, so
//! the final grid is the finest one whose whole histogram fits: it does not
//! depend on the order of the points.

use super::tile_plan::CellCount;

/// Keys sorted and merged at a time (8 MiB of keys, 8 MiB of scratch).
const BATCH: usize = 1 << 20;
/// Bits per radix pass.
const DIGIT: u32 = 11;

/// Counts per cell of a grid of `dims` cells.
pub(super) struct CellCounts {
    dims: [u64; 3],
    /// Cells are the given grid's cells shifted right by this many bits.
    level: u32,
    /// Most distinct cells the list may hold.
    cap: usize,
    /// Significant bits of a key.
    bits: u32,
    /// Sorted distinct keys and their counts.
    keys: Vec<u64>,
    counts: Vec<u32>,
    batch: Vec<u64>,
    scratch: Vec<u64>,
}

impl CellCounts {
    /// Counts over a grid of `dims` cells, holding at most `cap` (at least
    /// one) distinct cells.
    pub(super) fn new(dims: [u32; 3], cap: usize) -> Self {
        let dims = dims.map(|d| u64::from(d.max(1)));
        CellCounts {
            dims,
            level: 0,
            cap: cap.max(1),
            bits: key_bits(dims),
            keys: Vec::new(),
            counts: Vec::new(),
            batch: Vec::with_capacity(BATCH),
            scratch: Vec::new(),
        }
    }

    /// Adds one point to `cell` (inside the grid given to [`Self::new`]).
    #[inline]
    pub(super) fn add(&mut self, cell: [u32; 3]) {
        let [x, y, z] = cell.map(|c| u64::from(c >> self.level));
        self.batch.push(x + self.dims[0] * (y + self.dims[1] * z));
        if self.batch.len() == BATCH {
            self.merge_batch();
        }
    }

    /// Occupied cells and their counts, in key order, and how many times
    /// the grid was coarsened (cells are `2^level` given cells wide).
    pub(super) fn into_cells(mut self) -> (Vec<CellCount>, u32) {
        self.merge_batch();
        (self.batch, self.scratch) = (Vec::new(), Vec::new());
        let cells = self
            .keys
            .iter()
            .zip(&self.counts)
            .map(|(&k, &n)| (self.cell_of_key(k), u64::from(n)))
            .collect();
        (cells, self.level)
    }

    fn cell_of_key(&self, k: u64) -> [u32; 3] {
        let [nx, ny, _] = self.dims;
        [k % nx, k / nx % ny, k / nx / ny].map(|c| c as u32)
    }

    /// Halves the grid along each axis and merges the list down.
    fn coarsen(&mut self) {
        let old: Vec<[u32; 3]> = self.keys.iter().map(|&k| self.cell_of_key(k)).collect();
        self.level += 1;
        self.dims = self.dims.map(|d| d.div_ceil(2));
        self.bits = key_bits(self.dims);
        let [nx, ny, _] = self.dims;
        let mut pairs: Vec<(u64, u32)> = old
            .iter()
            .zip(&self.counts)
            .map(|(c, &n)| {
                let [x, y, z] = c.map(|v| u64::from(v >> 1));
                (x + nx * (y + ny * z), n)
            })
            .collect();
        pairs.sort_unstable_by_key(|p| p.0);
        self.keys.clear();
        self.counts.clear();
        for (k, n) in pairs {
            match self.keys.last() {
                Some(&last) if last == k => {
                    if let Some(c) = self.counts.last_mut() {
                        *c += n;
                    }
                }
                _ => {
                    self.keys.push(k);
                    self.counts.push(n);
                }
            }
        }
    }

    fn merge_batch(&mut self) {
        if self.batch.is_empty() {
            return;
        }
        radix_sort(&mut self.batch, &mut self.scratch, self.bits);
        let run_counts = run_lengths(&mut self.batch);
        let runs = &self.batch;
        let total = self.keys.len() + runs.len();
        let (mut keys, mut counts) = (Vec::with_capacity(total), Vec::with_capacity(total));
        let (mut i, mut j) = (0, 0);
        while i < self.keys.len() || j < runs.len() {
            let take_old = j == runs.len() || (i < self.keys.len() && self.keys[i] <= runs[j]);
            let take_new = i == self.keys.len() || (j < runs.len() && runs[j] <= self.keys[i]);
            let key = if take_old { self.keys[i] } else { runs[j] };
            let mut n = 0;
            if take_old {
                n += self.counts[i];
                i += 1;
            }
            if take_new {
                n += run_counts[j];
                j += 1;
            }
            keys.push(key);
            counts.push(n);
        }
        self.keys = keys;
        self.counts = counts;
        self.batch.clear();
        while self.keys.len() > self.cap {
            self.coarsen();
        }
    }
}

/// Significant bits of the keys of a grid of `dims` cells.
fn key_bits(dims: [u64; 3]) -> u32 {
    u64::BITS - (dims[0] * dims[1] * dims[2] - 1).leading_zeros()
}

/// Compacts sorted `keys` to their distinct values, returning how often
/// each occurred.
fn run_lengths(keys: &mut Vec<u64>) -> Vec<u32> {
    let mut counts: Vec<u32> = Vec::new();
    let mut distinct = 0;
    for i in 0..keys.len() {
        if distinct > 0 && keys[distinct - 1] == keys[i] {
            if let Some(c) = counts.last_mut() {
                *c += 1;
            }
        } else {
            keys[distinct] = keys[i];
            distinct += 1;
            counts.push(1);
        }
    }
    keys.truncate(distinct);
    counts
}

/// LSD radix sort of `keys` below `2^bits`, `DIGIT` bits a pass.
fn radix_sort(keys: &mut Vec<u64>, scratch: &mut Vec<u64>, bits: u32) {
    let mut shift = 0;
    while shift < bits {
        let mut start = vec![0usize; 1 << DIGIT];
        let digit = |k: u64| (k >> shift) as usize & ((1 << DIGIT) - 1);
        for &k in keys.iter() {
            start[digit(k)] += 1;
        }
        let mut sum = 0;
        for s in start.iter_mut() {
            (*s, sum) = (sum, sum + *s);
        }
        scratch.clear();
        scratch.resize(keys.len(), 0);
        for &k in keys.iter() {
            let d = digit(k);
            scratch[start[d]] = k;
            start[d] += 1;
        }
        std::mem::swap(keys, scratch);
        shift += DIGIT;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;

    #[test]
    fn counts_match_a_btree_map() {
        for seed in 0..5u64 {
            let mut rng = crate::rng::Rng::new(seed);
            let dims = [0u32; 3].map(|_| 1 + rng.below(1025) as u32);
            let mut table = CellCounts::new(dims, usize::MAX);
            let mut want: BTreeMap<[u32; 3], u64> = BTreeMap::new();
            // More than a batch for some seeds, so merges are exercised.
            let n = rng.below(3 * BATCH as u64);
            let hot = rng.below(4) as u32;
            for _ in 0..n {
                let c = [0, 1, 2].map(|a| {
                    let span = if a == 0 {
                        dims[0]
                    } else {
                        dims[a].min(hot + 1)
                    };
                    rng.below(span as u64) as u32
                });
                table.add(c);
                *want.entry(c).or_insert(0) += 1;
            }
            table.add(dims.map(|d| d - 1));
            *want.entry(dims.map(|d| d - 1)).or_insert(0) += 1;
            let (mut got, level) = table.into_cells();
            assert_eq!(level, 0);
            got.sort_unstable();
            let want: Vec<CellCount> = want.into_iter().collect();
            assert_eq!(got, want, "seed {seed}, dims {dims:?}");
        }
    }

    #[test]
    fn a_capped_list_coarsens_to_the_finest_grid_that_fits() {
        let mut rng = crate::rng::Rng::new(7);
        let dims = [1000u32, 700, 300];
        let cells: Vec<[u32; 3]> = (0..200_000)
            .map(|_| [0, 1, 2].map(|a| rng.below(dims[a] as u64) as u32))
            .collect();
        for cap in [50_000usize, 5_000, 100] {
            let mut table = CellCounts::new(dims, cap);
            cells.iter().for_each(|c| table.add(*c));
            let (got, level) = table.into_cells();
            assert!(got.len() <= cap, "cap {cap}");
            let at = |level: u32| -> BTreeMap<[u32; 3], u64> {
                let mut m = BTreeMap::new();
                for c in &cells {
                    *m.entry(c.map(|v| v >> level)).or_insert(0) += 1;
                }
                m
            };
            let want: Vec<CellCount> = at(level).into_iter().collect();
            let mut got = got;
            got.sort_unstable();
            assert_eq!(got, want, "cap {cap}");
            assert!(
                level == 0 || at(level - 1).len() > cap,
                "cap {cap}: too coarse"
            );
        }
    }

    #[test]
    fn radix_sort_sorts() {
        let mut rng = crate::rng::Rng::new(5);
        for bits in [1u32, 11, 12, 23, 31, 40] {
            let mut keys: Vec<u64> = (0..5000).map(|_| rng.below(1 << bits)).collect();
            let mut want = keys.clone();
            want.sort_unstable();
            radix_sort(&mut keys, &mut Vec::new(), bits);
            assert_eq!(keys, want, "bits {bits}");
        }
    }
}
