//! Disjoint sets over dense indices, with the index width chosen by the
//! caller (`u32` halves the memory of huge meshes; `u64` lifts the limit).
//!
//! Union links the larger root under the smaller, so every set's root is its
//! smallest member: results never depend on the order of unions, which keeps
//! the mesh metrics deterministic. Path halving keeps finds short.

/// An unsigned index type used for set members.
pub(crate) trait Slot: Copy + Ord + Send + Sync + std::fmt::Debug {
    fn from_usize(i: usize) -> Self;
    fn to_usize(self) -> usize;
    /// Whether every index below `n` fits this type.
    fn holds(n: usize) -> bool;
}

impl Slot for u32 {
    fn from_usize(i: usize) -> Self {
        i as u32
    }
    fn to_usize(self) -> usize {
        self as usize
    }
    fn holds(n: usize) -> bool {
        n <= u32::MAX as usize
    }
}

impl Slot for u64 {
    fn from_usize(i: usize) -> Self {
        i as u64
    }
    fn to_usize(self) -> usize {
        self as usize
    }
    fn holds(_n: usize) -> bool {
        true
    }
}

/// Plain disjoint sets: `parent[i] == i` marks a root.
pub(crate) struct DisjointSets<S: Slot> {
    parent: Vec<S>,
}

impl<S: Slot> DisjointSets<S> {
    pub fn new(n: usize) -> Self {
        DisjointSets {
            parent: (0..n).map(S::from_usize).collect(),
        }
    }

    pub fn find(&mut self, mut x: usize) -> usize {
        loop {
            let p = self.parent[x].to_usize();
            if p == x {
                return x;
            }
            let gp = self.parent[p];
            self.parent[x] = gp;
            x = gp.to_usize();
        }
    }

    /// Joins the sets of `a` and `b`; returns whether they were apart.
    pub fn union(&mut self, a: usize, b: usize) -> bool {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra == rb {
            return false;
        }
        let (lo, hi) = if ra < rb { (ra, rb) } else { (rb, ra) };
        self.parent[hi] = S::from_usize(lo);
        true
    }

    pub fn is_root(&self, x: usize) -> bool {
        self.parent[x].to_usize() == x
    }
}

/// Disjoint sets that also carry a parity bit per member relative to its
/// root: the classic structure for two-colouring (here: whether a triangle
/// must be flipped to agree with its neighbours).
pub(crate) struct ParitySets<S: Slot> {
    parent: Vec<S>,
    /// Parity of each member relative to its parent.
    parity: Vec<bool>,
}

impl<S: Slot> ParitySets<S> {
    pub fn new(n: usize) -> Self {
        ParitySets {
            parent: (0..n).map(S::from_usize).collect(),
            parity: vec![false; n],
        }
    }

    /// Root of `x` and the parity of `x` relative to that root.
    pub fn find(&mut self, mut x: usize) -> (usize, bool) {
        // Two passes: find the root and the total parity, then compress.
        let start = x;
        let mut total = false;
        loop {
            let p = self.parent[x].to_usize();
            if p == x {
                break;
            }
            total ^= self.parity[x];
            x = p;
        }
        let root = x;
        let mut y = start;
        let mut rel = total;
        while y != root {
            let next = self.parent[y].to_usize();
            let next_rel = rel ^ self.parity[y];
            self.parent[y] = S::from_usize(root);
            self.parity[y] = rel;
            y = next;
            rel = next_rel;
        }
        (root, total)
    }

    /// Requires `parity(a) ^ parity(b) == differ`. Returns `false` when that
    /// contradicts the constraints already joined (an odd cycle).
    pub fn relate(&mut self, a: usize, b: usize, differ: bool) -> bool {
        let (ra, pa) = self.find(a);
        let (rb, pb) = self.find(b);
        if ra == rb {
            return (pa ^ pb) == differ;
        }
        let (lo, hi) = if ra < rb { (ra, rb) } else { (rb, ra) };
        self.parent[hi] = S::from_usize(lo);
        self.parity[hi] = pa ^ pb ^ differ;
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn roots_are_smallest_members() {
        let mut s = DisjointSets::<u32>::new(6);
        s.union(4, 5);
        s.union(5, 2);
        s.union(0, 1);
        assert_eq!(s.find(4), 2);
        assert_eq!(s.find(1), 0);
        assert!(!s.union(2, 4));
        assert!(s.is_root(3));
    }

    #[test]
    fn parity_detects_odd_cycles() {
        let mut p = ParitySets::<u64>::new(4);
        assert!(p.relate(0, 1, true));
        assert!(p.relate(1, 2, true));
        assert!(p.relate(0, 2, false));
        assert!(!p.relate(2, 0, true));
        assert!(p.relate(3, 2, false));
        assert_eq!(p.find(3), (0, false));
        assert_eq!(p.find(1), (0, true));
    }
}
