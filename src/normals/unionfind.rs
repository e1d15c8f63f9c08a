//! The union-finds of the spanning-forest passes (paper 1 section 2.4).
//!
//! [`ParityUnionFind`]: every element carries a parity bit relative to its
//! parent: joining `a` and `b` with parity `p` records "a and b differ by p".
//! Following the parities along find paths gives each point's flip relative
//! to its component's root, which is how the global pass orients normals
//! without ever storing the tree (ARCHITECTURE.md, normal orientation).
//!
//! [`UnionFind`]: plain connectivity for a tile's own forest, which needs no
//! parities (the global pass derives them from the forest's edge signs).

/// Parity union-find over `0..n` (u32 ids: 5 bytes and 1 bit per element).
#[derive(Clone, Debug)]
pub struct ParityUnionFind {
    parent: Vec<u32>,
    rank: Vec<u8>,
    parity: Vec<u64>,
}

impl ParityUnionFind {
    pub fn new(n: usize) -> Self {
        ParityUnionFind {
            parent: (0..n as u32).collect(),
            rank: vec![0; n],
            parity: vec![0; n.div_ceil(64)],
        }
    }

    pub fn len(&self) -> usize {
        self.parent.len()
    }

    pub fn is_empty(&self) -> bool {
        self.parent.is_empty()
    }

    /// Drops the ranks (no more unions will be made).
    pub(super) fn free_ranks(&mut self) {
        self.rank = Vec::new();
    }

    /// Points every element at its root, its bit then being its parity to
    /// the root (in id order; roots keep bit 0, as a root's bit is never
    /// set).
    pub(super) fn flatten(&mut self) {
        for i in 0..self.parent.len() as u32 {
            let (root, parity) = self.find(i);
            self.parent[i as usize] = root;
            self.set_bit(i, parity);
        }
    }

    /// The parent and parity arrays.
    pub(super) fn into_parts(self) -> (Vec<u32>, Vec<u64>) {
        (self.parent, self.parity)
    }

    fn bit(&self, i: u32) -> bool {
        self.parity[i as usize / 64] >> (i % 64) & 1 == 1
    }

    fn set_bit(&mut self, i: u32, v: bool) {
        let w = &mut self.parity[i as usize / 64];
        let m = 1u64 << (i % 64);
        if v {
            *w |= m
        } else {
            *w &= !m
        }
    }

    /// Root of `i` and the parity of `i` relative to it. Path halving: each
    /// node on the way is pointed at its grandparent, its parity bit becoming
    /// the sum of the two it skips (one pass; the ranks, and so every later
    /// root choice, do not depend on how paths are shortened).
    pub fn find(&mut self, mut i: u32) -> (u32, bool) {
        let mut acc = false;
        loop {
            let p = self.parent[i as usize];
            let g = self.parent[p as usize];
            if p == g {
                return (p, acc ^ (p != i && self.bit(i)));
            }
            let to_g = self.bit(i) ^ self.bit(p);
            self.parent[i as usize] = g;
            self.set_bit(i, to_g);
            acc ^= to_g;
            i = g;
        }
    }

    /// [`Self::union`] of each `(a, b, parity)` in order. What the unions
    /// will read is read for the whole batch first (each endpoint's parent,
    /// grandparent, the grandparent's rank, their parity words):
    /// independent loads the CPU overlaps, where one union at a time waits
    /// for each cache miss in turn (Kruskal over input ids jumps randomly
    /// through the arrays). The unions then find those slots in cache.
    pub fn union_batch(&mut self, batch: &[(u32, u32, bool)]) {
        let mut touched = 0u64;
        for &(a, b, _) in batch {
            for i in [a, b] {
                let p = self.parent[i as usize];
                let g = self.parent[p as usize];
                touched ^= u64::from(self.rank[g as usize])
                    ^ self.parity[i as usize / 64]
                    ^ self.parity[p as usize / 64];
            }
        }
        std::hint::black_box(touched);
        for &(a, b, parity) in batch {
            self.union(a, b, parity);
        }
    }

    /// Joins the sets of `a` and `b`, recording that they differ by `parity`.
    /// Returns false (and changes nothing) when they were already joined.
    pub fn union(&mut self, a: u32, b: u32, parity: bool) -> bool {
        let (ra, pa) = self.find(a);
        let (rb, pb) = self.find(b);
        if ra == rb {
            return false;
        }
        let rel = pa ^ pb ^ parity;
        let (child, root) = if self.rank[ra as usize] < self.rank[rb as usize] {
            (ra, rb)
        } else {
            (rb, ra)
        };
        self.parent[child as usize] = root;
        self.set_bit(child, rel);
        if self.rank[ra as usize] == self.rank[rb as usize] {
            self.rank[root as usize] += 1;
        }
        true
    }
}

/// Union-find over `0..n` without parities: union by rank, path halving,
/// u32 parents (5 bytes per element).
#[derive(Clone, Debug)]
pub struct UnionFind {
    parent: Vec<u32>,
    rank: Vec<u8>,
}

impl UnionFind {
    pub fn new(n: usize) -> Self {
        UnionFind {
            parent: (0..n as u32).collect(),
            rank: vec![0; n],
        }
    }

    /// Root of `i`; every node on the way is pointed at its grandparent
    /// (path halving: one pass, no stack).
    pub fn find(&mut self, mut i: u32) -> u32 {
        loop {
            let p = self.parent[i as usize];
            let g = self.parent[p as usize];
            if p == g {
                return p;
            }
            self.parent[i as usize] = g;
            i = g;
        }
    }

    /// Whether `a` and `b` are in one set.
    pub fn connected(&mut self, a: u32, b: u32) -> bool {
        self.find(a) == self.find(b)
    }

    /// Joins the sets of `a` and `b`; false (and no change) when they were
    /// already joined.
    pub fn union(&mut self, a: u32, b: u32) -> bool {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra == rb {
            return false;
        }
        let (lo, hi) = (self.rank[ra as usize], self.rank[rb as usize]);
        let (child, root) = if lo < hi { (ra, rb) } else { (rb, ra) };
        self.parent[child as usize] = root;
        if lo == hi {
            self.rank[root as usize] += 1;
        }
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Components by brute force: label propagation until nothing changes.
    fn brute_components(n: usize, pairs: &[(u32, u32)]) -> Vec<usize> {
        let mut label: Vec<usize> = (0..n).collect();
        loop {
            let mut changed = false;
            for &(a, b) in pairs {
                let m = label[a as usize].min(label[b as usize]);
                for v in [a, b] {
                    if label[v as usize] != m {
                        label[v as usize] = m;
                        changed = true;
                    }
                }
            }
            if !changed {
                return label;
            }
        }
    }

    #[test]
    fn parities_match_brute_force_relabelling() {
        for seed in 0..20u64 {
            let mut rng = crate::rng::Rng::new(seed);
            let n = 1 + rng.below(300) as usize;
            // Brute force: every element's component label and parity to it.
            let mut label: Vec<usize> = (0..n).collect();
            let mut par = vec![false; n];
            let mut uf = ParityUnionFind::new(n);
            for _ in 0..rng.below(600) {
                let (a, b) = (rng.below(n as u64) as u32, rng.below(n as u64) as u32);
                let p = rng.below(2) == 1;
                let (la, lb) = (label[a as usize], label[b as usize]);
                assert_eq!(uf.union(a, b, p), la != lb, "seed {seed}: union({a}, {b})");
                if la != lb {
                    let flip = par[a as usize] ^ par[b as usize] ^ p;
                    for v in 0..n {
                        if label[v] == lb {
                            label[v] = la;
                            par[v] ^= flip;
                        }
                    }
                }
                let (c, d) = (rng.below(n as u64) as u32, rng.below(n as u64) as u32);
                let ((rc, pc), (rd, pd)) = (uf.find(c), uf.find(d));
                assert_eq!(
                    rc == rd,
                    label[c as usize] == label[d as usize],
                    "seed {seed}"
                );
                if rc == rd {
                    let want = par[c as usize] ^ par[d as usize];
                    assert_eq!(pc ^ pd, want, "seed {seed}: parity {c} ~ {d}");
                }
            }
        }
    }

    #[test]
    fn plain_union_find_matches_brute_force_components() {
        for seed in 0..20u64 {
            let mut rng = crate::rng::Rng::new(seed);
            let n = 1 + rng.below(200) as usize;
            let pairs: Vec<(u32, u32)> = (0..rng.below(300))
                .map(|_| (rng.below(n as u64) as u32, rng.below(n as u64) as u32))
                .collect();
            let mut uf = UnionFind::new(n);
            let mut joins = 0;
            for &(a, b) in &pairs {
                let before = uf.connected(a, b);
                let joined = uf.union(a, b);
                assert_eq!(joined, !before, "seed {seed}: union({a}, {b})");
                joins += joined as usize;
            }
            let label = brute_components(n, &pairs);
            let mut comps = label.clone();
            comps.sort_unstable();
            comps.dedup();
            assert_eq!(n - joins, comps.len(), "seed {seed}: component count");
            for a in 0..n as u32 {
                for b in 0..n as u32 {
                    let same = label[a as usize] == label[b as usize];
                    assert_eq!(uf.connected(a, b), same, "seed {seed}: {a} ~ {b}");
                }
            }
        }
    }

    #[test]
    fn parity_follows_chains() {
        let mut uf = ParityUnionFind::new(6);
        assert!(uf.union(0, 1, true));
        assert!(uf.union(1, 2, true));
        assert!(uf.union(3, 4, false));
        assert!(uf.union(2, 4, true));
        assert!(!uf.union(0, 4, false));
        let rel = |uf: &mut ParityUnionFind, a, b| {
            let (ra, pa) = uf.find(a);
            let (rb, pb) = uf.find(b);
            assert_eq!(ra, rb);
            pa ^ pb
        };
        assert!(rel(&mut uf, 0, 1));
        assert!(!rel(&mut uf, 0, 2));
        assert!(rel(&mut uf, 0, 4));
        assert!(rel(&mut uf, 0, 3));
        assert_ne!(uf.find(5).0, uf.find(0).0);
    }

    #[test]
    fn long_chain_compresses_correctly() {
        let n = 1000u32;
        let mut uf = ParityUnionFind::new(n as usize);
        for i in 1..n {
            uf.union(i - 1, i, i % 3 == 0);
        }
        let (r0, p0) = uf.find(0);
        let mut expect = false;
        for i in 1..n {
            expect ^= i % 3 == 0;
            let (r, p) = uf.find(i);
            assert_eq!(r, r0);
            assert_eq!(p ^ p0, expect, "point {i}");
        }
    }
}
