//! Spanning forests over Riemannian-graph edges (paper 1 section 2.4, edge
//! cost `1 - |n_i . n_j|`).
//!
//! Deviation from the paper, for tiling: instead of walking the tree with
//! Prim's algorithm from the root, each tile keeps the minimum spanning forest
//! of its own edges (Kruskal), and one global Kruskal pass over the union of
//! the tiles' forests finds the same tree (cycle property; ties broken by
//! point ids make the tree unique). The flip of each point relative to the
//! root is the parity of its tree path, as Prim's walk would set it.
//!
//! This module owns the edge type and a tile's forest. Implementation
//! choice: the forest is found by filter-Kruskal (Osipov, Sanders, Singler,
//! "The filter-Kruskal minimum spanning tree algorithm", ALENEX 2009), not by
//! sorting every edge: a Riemannian graph has about six edges per point and
//! only one per point ends in the forest, so after Kruskal on the lighter
//! half, most heavy edges already close a cycle and are dropped unsorted.
//! The result (edges and order) is that of plain Kruskal on the sorted edges.

use super::unionfind::UnionFind;

/// A Riemannian-graph edge between two points (input-order ids, `a < b`).
/// `w` is the cost `1 - |n_a . n_b|` carrying the sign of `n_a . n_b`, so a
/// negative `w` means "flip one of the two".
///
/// The ids order the edges (and so choose the tree); `slots` are where the
/// global union-find keeps the two ends (their store indices), so Kruskal
/// walks the union-find in the store's spatial order where input ids jump
/// at random (10M points: the orientation passes 4.3 s -> 2.7 s). Slots
/// never enter `Edge::key`, so the tree does not depend on the tiling.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Edge {
    /// Edge cost, its sign bit set when the edge flips the orientation (`n_a . n_b < 0`).
    pub w: f64,
    /// Store index of one end.
    pub a: u32,
    /// Store index of the other end.
    pub b: u32,
    /// Union-find slots of `a` and `b`, in that order.
    pub slots: [u32; 2],
}

/// Whether every edge names points (and slots) of a store of `points`
/// points and has a cost the edge order can rank.
pub(crate) fn edges_fit(edges: &[Edge], points: u64) -> bool {
    edges.iter().all(|e| {
        let ids = [e.a, e.b, e.slots[0], e.slots[1]];
        ids.iter().all(|&i| u64::from(i) < points) && !e.w.is_nan()
    })
}

impl Edge {
    /// The paper's edge: cost `1 - |n_a . n_b|`.
    pub fn new(a: u32, b: u32, dot: f64) -> Self {
        Edge::with_cost(a, b, 1.0 - dot.abs(), dot)
    }

    /// An edge of any non-negative cost; `dot` only gives the flip sign.
    /// Slots are the ids (for graphs whose ids are their own slots).
    pub fn with_cost(a: u32, b: u32, cost: f64, dot: f64) -> Self {
        Edge::between([a, a], [b, b], cost, dot)
    }

    /// As [`Edge::with_cost`], each end given as `[id, slot]`.
    pub(crate) fn between(x: [u32; 2], y: [u32; 2], cost: f64, dot: f64) -> Self {
        let w = cost.max(0.0).copysign(dot);
        let (x, y) = if x[0] < y[0] { (x, y) } else { (y, x) };
        Edge {
            w,
            a: x[0],
            b: y[0],
            slots: [x[1], y[1]],
        }
    }

    /// Total order used everywhere: cost, then the two ids.
    pub(crate) fn key(&self) -> (u64, u32, u32) {
        (self.w.abs().to_bits(), self.a, self.b)
    }

    pub(crate) fn flips(&self) -> bool {
        self.w.is_sign_negative()
    }

    /// Bytes of one edge on disk.
    pub const BYTES: usize = 24;

    pub(crate) fn to_bytes(self) -> [u8; Self::BYTES] {
        let mut out = [0u8; Self::BYTES];
        out[..8].copy_from_slice(&self.w.to_le_bytes());
        let words = [self.a, self.b, self.slots[0], self.slots[1]];
        for (k, v) in words.iter().enumerate() {
            out[8 + 4 * k..12 + 4 * k].copy_from_slice(&v.to_le_bytes());
        }
        out
    }

    pub(crate) fn from_bytes(b: &[u8; Self::BYTES]) -> Self {
        let word = |k: usize| u32::from_le_bytes([b[k], b[k + 1], b[k + 2], b[k + 3]]);
        let mut w = [0u8; 8];
        w.copy_from_slice(&b[..8]);
        Edge {
            w: f64::from_le_bytes(w),
            a: word(8),
            b: word(12),
            slots: [word(16), word(20)],
        }
    }
}

/// Minimum spanning forest of `edges` over `n` local vertices, in
/// `Edge::key` order. The same as sorting by key, dropping repeats of a
/// pair and running Kruskal, but computed by filter-Kruskal (see the module
/// doc); a pair given twice with one key and both signs keeps the sign that
/// sorts first by the `w` bits (a tie the old sort left to chance).
///
/// The edges' slots are the ends' dense local numbers (`0..n` in a tile),
/// every one below `n`; the forest's edges keep them, for the caller to
/// turn into store indices.
pub fn spanning_forest(edges: Vec<Edge>, n: usize) -> Vec<Edge> {
    forest_sorting_below(edges, n, SORT_DIRECTLY)
}

/// The plain algorithm [`spanning_forest`] must equal: sort every edge by
/// key, drop repeats of a pair, Kruskal. Kept as the oracle of the tests
/// and the baseline of `benches/forest.rs`, not for the kernel.
#[doc(hidden)]
pub fn reference_forest(mut edges: Vec<Edge>, n: usize) -> Vec<Edge> {
    edges.sort_unstable_by_key(|e| e.key());
    edges.dedup_by_key(|e| (e.a, e.b));
    let mut uf = UnionFind::new(n);
    edges
        .into_iter()
        .filter(|e| uf.union(e.slots[0], e.slots[1]))
        .collect()
}

/// [`spanning_forest`] with parts of at most `base` edges sorted directly.
fn forest_sorting_below(mut edges: Vec<Edge>, n: usize, base: usize) -> Vec<Edge> {
    let mut uf = UnionFind::new(n);
    let mut out = Vec::with_capacity(edges.len().min(n.saturating_sub(1)));
    let depth = 2 * (usize::BITS - edges.len().leading_zeros());
    let parts = Parts { base, depth };
    parts.filter_kruskal(&mut edges, &mut uf, &mut out);
    out
}

/// Parts at most this long are sorted and run through Kruskal directly.
const SORT_DIRECTLY: usize = 1 << 12;

/// Number of evenly spaced keys whose median is the pivot.
const PIVOT_SAMPLE: usize = 63;

/// [`Edge::key`] then the sign of `w`, packed so that one integer compare
/// orders edges: `|w|` bits use 63 bits (the sign bit of `|w|` is 0).
fn sort_key(e: &Edge) -> u128 {
    let (w, a, b) = e.key();
    let sign = e.w.is_sign_negative() as u128;
    (w as u128) << 65 | (a as u128) << 33 | (b as u128) << 1 | sign
}

/// How filter-Kruskal splits: parts of at most `base` edges are sorted
/// directly, and so is any part once `depth` splits were used on the way down
/// (introsort's guard against unlucky pivots).
#[derive(Clone, Copy)]
struct Parts {
    base: usize,
    depth: u32,
}

impl Parts {
    /// Kruskal on `edges` with the forest so far in `uf`: the light part
    /// (keys up to a sampled median) first, then what of the heavy part still
    /// joins two components.
    fn filter_kruskal(mut self, mut edges: &mut [Edge], uf: &mut UnionFind, out: &mut Vec<Edge>) {
        loop {
            if edges.len() <= self.base || self.depth == 0 {
                return sorted_kruskal(edges, uf, out);
            }
            self.depth -= 1;
            let light = partition(edges, pivot_key(edges));
            if light == edges.len() {
                // The pivot is the largest key: nothing to split off.
                return sorted_kruskal(edges, uf, out);
            }
            let (lo, hi) = edges.split_at_mut(light);
            self.filter_kruskal(lo, uf, out);
            let kept = retain_joining(hi, uf);
            edges = &mut hi[..kept];
        }
    }
}

fn sorted_kruskal(edges: &mut [Edge], uf: &mut UnionFind, out: &mut Vec<Edge>) {
    edges.sort_unstable_by_key(sort_key);
    // A repeated pair is rejected by `union` once its first copy is in.
    out.extend(
        edges
            .iter()
            .filter(|e| uf.union(e.slots[0], e.slots[1]))
            .copied(),
    );
}

/// Median key of a deterministic, evenly spaced sample (`edges` not empty).
fn pivot_key(edges: &[Edge]) -> u128 {
    let count = PIVOT_SAMPLE.min(edges.len());
    let step = edges.len() / count;
    let mut sample: Vec<u128> = (0..count)
        .map(|i| sort_key(&edges[i * step + step / 2]))
        .collect();
    *sample.select_nth_unstable(count / 2).1
}

/// Moves the edges with keys `<= pivot` to the front; returns their count.
fn partition(edges: &mut [Edge], pivot: u128) -> usize {
    let (mut i, mut j) = (0, edges.len());
    loop {
        while i < j && sort_key(&edges[i]) <= pivot {
            i += 1;
        }
        while i < j && sort_key(&edges[j - 1]) > pivot {
            j -= 1;
        }
        if i >= j {
            return i;
        }
        edges.swap(i, j - 1);
        i += 1;
        j -= 1;
    }
}

/// Keeps (in order, at the front) the edges whose ends are not yet joined;
/// returns their count. The others would close a cycle of lighter edges.
fn retain_joining(edges: &mut [Edge], uf: &mut UnionFind) -> usize {
    let mut kept = 0;
    for k in 0..edges.len() {
        let e = edges[k];
        if !uf.connected(e.slots[0], e.slots[1]) {
            edges[kept] = e;
            kept += 1;
        }
    }
    kept
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// A random graph on `n` vertices whose ids are a shuffled spread of the
    /// local numbers; costs from `levels` distinct values (many ties), every
    /// `repeat`-th edge given twice (reversed, as from its other end), and
    /// only the first `n - gap` vertices used (the rest isolated).
    fn random_edges(seed: u64, n: usize, m: usize, levels: u64, repeat: usize) -> Vec<Edge> {
        let mut rng = crate::rng::Rng::new(seed);
        let ids: Vec<u32> = (0..n as u32).map(|i| i * 3 + (i % 2) * 7).collect();
        let used = (n - n / 10).max(1) as u64;
        let mut edges = Vec::new();
        for k in 0..m {
            let (i, j) = (rng.below(used) as u32, rng.below(used) as u32);
            if i == j {
                continue;
            }
            let cost = rng.below(levels) as f64 / levels as f64;
            // The sign is the pair's, as in the kernels (a pair given with
            // one key and both signs is the tie the oracle leaves to chance).
            let dot = if (i ^ j) % 3 == 0 { -0.5 } else { 0.5 };
            let (x, y) = ([ids[i as usize], i], [ids[j as usize], j]);
            edges.push(Edge::between(x, y, cost, dot));
            if repeat > 0 && k % repeat == 0 {
                edges.push(Edge::between(y, x, cost, dot));
            }
        }
        edges
    }

    fn same_as_oracle(edges: Vec<Edge>, n: usize, what: &str) {
        let want = reference_forest(edges.clone(), n);
        let got = spanning_forest(edges, n);
        assert_eq!(got.len(), want.len(), "{what}: forest size");
        for (k, (g, w)) in got.iter().zip(&want).enumerate() {
            assert_eq!(g.w.to_bits(), w.w.to_bits(), "{what}: edge {k} cost");
            assert_eq!((g.a, g.b), (w.a, w.b), "{what}: edge {k} ends");
        }
    }

    #[test]
    fn large_graphs_match_sorted_kruskal() {
        // Big enough to take several filter rounds below the sort threshold.
        for (seed, n, levels) in [(1, 20_000, 7), (2, 30_000, 1 << 20), (3, 5_000, 1)] {
            let edges = random_edges(seed, n, 6 * n, levels, 5);
            same_as_oracle(
                edges,
                n,
                &format!("seed {seed}, n {n}, {levels} cost levels"),
            );
        }
    }

    #[test]
    fn degenerate_inputs_match_sorted_kruskal() {
        assert!(spanning_forest(Vec::new(), 0).is_empty());
        assert!(spanning_forest(Vec::new(), 5).is_empty());
        let self_loop = Edge::between([4, 0], [4, 0], 0.1, 0.9);
        assert!(spanning_forest(vec![self_loop; 3], 1).is_empty());
        // One pair, many copies: one forest edge.
        let e = Edge::between([2, 0], [9, 1], 0.7, -0.3);
        same_as_oracle(vec![e; 10_000], 2, "one pair repeated");
    }

    #[test]
    fn a_pair_with_both_signs_keeps_the_positive_one_in_any_order() {
        let plus = Edge::between([1, 0], [5, 1], 0.75, 0.25);
        let minus = Edge::between([1, 0], [5, 1], 0.75, -0.25);
        for input in [vec![plus, minus], vec![minus, plus]] {
            let got = spanning_forest(input, 2);
            assert_eq!(got, vec![plus]);
        }
    }

    proptest! {
        #[test]
        fn small_graphs_match_sorted_kruskal(
            seed in 0u64..1_000_000,
            n in 1usize..300,
            per_vertex in 0usize..8,
            levels in 1u64..6,
            repeat in 0usize..4,
        ) {
            let edges = random_edges(seed, n, n * per_vertex, levels, repeat);
            let want = reference_forest(edges.clone(), n);
            for base in [1, 16, SORT_DIRECTLY] {
                let got = forest_sorting_below(edges.clone(), n, base);
                prop_assert_eq!(
                    got.iter().map(|e| (e.w.to_bits(), e.a, e.b)).collect::<Vec<_>>(),
                    want.iter().map(|e| (e.w.to_bits(), e.a, e.b)).collect::<Vec<_>>(),
                    "seed {}, n {}, sorted below {}", seed, n, base
                );
            }
        }
    }

    #[test]
    fn edge_sign_and_bytes_round_trip() {
        let e = Edge::new(7, 3, -0.9);
        assert_eq!((e.a, e.b), (3, 7));
        assert!(e.flips());
        assert!((e.w.abs() - 0.1).abs() < 1e-12);
        assert_eq!(Edge::from_bytes(&e.to_bytes()), e);
        // Slots follow their ids when the ends swap.
        let s = Edge::between([9, 40], [2, 11], 0.5, 1.0);
        assert_eq!((s.a, s.b, s.slots), (2, 9, [11, 40]));
        assert_eq!(Edge::from_bytes(&s.to_bytes()), s);
        assert!(Edge::new(1, 2, -1.0).flips());
        assert!(!Edge::new(1, 2, 1.0).flips());
    }

    #[test]
    fn forest_keeps_cheapest_edges() {
        // Square 0-1-2-3 with one diagonal; the heaviest cycle edges go.
        let edges = [
            (0, 1, 0.9),
            (1, 2, 0.99),
            (2, 3, 0.8),
            (3, 0, 0.95),
            (0, 2, 0.5),
        ]
        .map(|(a, b, d)| Edge::new(a, b, d))
        .to_vec();
        let edges = spanning_forest(edges, 4);
        assert_eq!(edges.len(), 3);
        let kept: Vec<_> = edges.iter().map(|e| (e.a, e.b)).collect();
        assert_eq!(kept, vec![(1, 2), (0, 3), (0, 1)]);
    }
}
