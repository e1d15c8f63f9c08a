//! The finished partition of the orientation's parity union-find: dense
//! component labels and parities to the roots (paper 1 section 2.4, after
//! Kruskal). Built in place from the union-find, so the global passes that
//! follow do one array read per point.

use super::unionfind::ParityUnionFind;

/// The finished partition of a [`ParityUnionFind`]: every element's
/// component, numbered `0..count` in order of each component's smallest
/// element, and its parity relative to the component's root. Lookups are
/// one array read (no path walks, no mutation), so passes can share it
/// across threads, and per-component data can live in a `Vec`.
#[derive(Clone, Debug)]
pub struct Components {
    label: Vec<u32>,
    parity: Vec<u64>,
    /// Each component's union-find root (the element `find` returned).
    roots: Vec<u32>,
}

impl Components {
    /// Component label and parity relative to the root of element `i`.
    #[inline]
    pub fn get(&self, i: u32) -> (u32, bool) {
        let bit = self.parity[i as usize / 64] >> (i % 64) & 1 == 1;
        (self.label[i as usize], bit)
    }

    /// Number of components.
    pub fn count(&self) -> usize {
        self.roots.len()
    }

    /// The union-find root of component `label`.
    pub fn root(&self, label: u32) -> u32 {
        self.roots[label as usize]
    }
}

impl ParityUnionFind {
    /// Flattens the forest and numbers its trees, in place: the parent array
    /// becomes the label array and the ranks are freed first, so the peak
    /// stays that of the union-find (plus a bit per element while numbering).
    pub fn into_components(mut self) -> Components {
        let n = self.len() as u32;
        self.free_ranks();
        self.flatten();
        let (mut label, parity) = self.into_parts();
        // Number roots at their first member; a numbered root's slot holds
        // its label (marked in `done`), every other slot still its root.
        let mut done = vec![0u64; (n as usize).div_ceil(64)];
        let mut roots = Vec::new();
        let is_done = |done: &[u64], r: u32| done[r as usize / 64] >> (r % 64) & 1 == 1;
        for i in 0..n {
            if is_done(&done, i) {
                continue;
            }
            let r = label[i as usize];
            let l = if is_done(&done, r) {
                label[r as usize]
            } else {
                let l = roots.len() as u32;
                roots.push(r);
                done[r as usize / 64] |= 1 << (r % 64);
                label[r as usize] = l;
                l
            };
            label[i as usize] = l;
        }
        Components {
            label,
            parity,
            roots,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn components_agree_with_find() {
        for seed in 0..20u64 {
            let mut rng = crate::rng::Rng::new(seed);
            let n = 1 + rng.below(400) as usize;
            let mut uf = ParityUnionFind::new(n);
            for _ in 0..rng.below(500) {
                let (a, b) = (rng.below(n as u64) as u32, rng.below(n as u64) as u32);
                uf.union(a, b, rng.below(2) == 1);
            }
            let mut reference = uf.clone();
            let comps = uf.into_components();
            let mut first_of_label = Vec::new();
            for i in 0..n as u32 {
                let (root, parity) = reference.find(i);
                let (label, bit) = comps.get(i);
                assert_eq!(bit, parity, "seed {seed}: parity of {i}");
                assert_eq!(comps.root(label), root, "seed {seed}: root of {i}");
                // Labels are dense, numbered by each component's first member.
                if label as usize == first_of_label.len() {
                    first_of_label.push(i);
                }
                assert!((label as usize) < first_of_label.len(), "seed {seed}: {i}");
            }
            assert_eq!(comps.count(), first_of_label.len(), "seed {seed}");
            let mut roots: Vec<u32> = (0..comps.count() as u32).map(|l| comps.root(l)).collect();
            roots.sort_unstable();
            roots.dedup();
            assert_eq!(
                roots.len(),
                comps.count(),
                "seed {seed}: one label per root"
            );
        }
    }
}
