//! Union-find whose every element carries a parity bit relative to its
//! parent: joining `a` and `b` with parity `p` records "a and b differ by p".
//! Following the parities along find paths gives each point's flip relative
//! to its component's root, which is how the spanning forest orients normals
//! without ever storing the tree (ARCHITECTURE.md, normal orientation).

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

    /// Root of `i` and the parity of `i` relative to it; compresses the path.
    pub fn find(&mut self, i: u32) -> (u32, bool) {
        let mut root = i;
        let mut acc = false;
        while self.parent[root as usize] != root {
            acc ^= self.bit(root);
            root = self.parent[root as usize];
        }
        // Second walk: point every node at the root with its full parity.
        let mut cur = i;
        let mut cur_par = acc;
        while self.parent[cur as usize] != root && cur != root {
            let next = self.parent[cur as usize];
            let next_par = cur_par ^ self.bit(cur);
            self.parent[cur as usize] = root;
            self.set_bit(cur, cur_par);
            cur = next;
            cur_par = next_par;
        }
        (root, acc)
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

#[cfg(test)]
mod tests {
    use super::*;

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
