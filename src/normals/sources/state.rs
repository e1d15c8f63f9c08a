//! The propagation's state, which both orders (`stacks`, `best_first`)
//! share and [`super::propagate`] drives: the cloud as the propagation sees
//! it ([`Cloud`]), each point's sign and whether it is decided, and the
//! roots of the parts no pair reaches; with the one rule that signs a root
//! ([`faces_away`]), which the tiled and external passes apply too.

use super::graph::Graph;
use super::pairs::{End, PairRule};
use crate::normals::forest::Edge;
use glam::DVec3;

/// One cloud as the propagation sees it.
pub(crate) struct Cloud<'a> {
    pub points: &'a [DVec3],
    pub normals: &'a [Option<DVec3>],
    pub ids: &'a [u32],
    pub graph: &'a Graph,
    pub rule: PairRule,
    /// Direction of the first source: roots parts no pair reaches.
    pub first_direction: DVec3,
}

/// Whether `n` must flip to face `d` (the one rule for every root).
pub fn faces_away(n: DVec3, d: DVec3) -> bool {
    n.dot(d) < 0.0
}

/// The propagation state both orders share.
pub(crate) struct State<'c, 'a> {
    pub c: &'c Cloud<'a>,
    pub flip: Vec<bool>,
    /// bNormal: the point's sign is decided.
    pub done: Vec<bool>,
    /// Points with a normal, by decreasing extent along the first source
    /// direction (ties by id): the roots of parts no pair reaches.
    roots: Vec<u32>,
    next_root: usize,
}

impl<'c, 'a> State<'c, 'a> {
    /// Nothing decided yet (`propagate` starts the sources).
    pub fn new(c: &'c Cloud<'a>) -> Self {
        let n = c.points.len();
        let mut roots: Vec<u32> = (0..n as u32)
            .filter(|&i| c.normals[i as usize].is_some())
            .collect();
        let key = |i: u32| c.points[i as usize].dot(c.first_direction);
        roots.sort_unstable_by(|&a, &b| {
            key(b)
                .total_cmp(&key(a))
                .then(c.ids[a as usize].cmp(&c.ids[b as usize]))
        });
        State {
            c,
            flip: vec![false; n],
            done: vec![false; n],
            roots,
            next_root: 0,
        }
    }

    pub fn normal(&self, i: usize) -> Option<DVec3> {
        self.c.normals.get(i).copied().flatten()
    }

    /// The pair `(i, j)` as an edge (both must have a normal).
    pub fn edge(&self, i: usize, j: usize) -> Option<Edge> {
        let end = |k: usize| {
            self.normal(k).map(|n| End {
                id: self.c.ids[k],
                // In memory there is no union-find: the slot is unused.
                slot: k as u32,
                p: self.c.points[k],
                n,
            })
        };
        Some(self.c.rule.edge(end(i)?, end(j)?))
    }

    pub fn start(&mut self, i: usize, flip: bool) {
        self.flip[i] = flip;
        self.done[i] = true;
    }

    /// Adjusts `j` from the adjusted `o` across a pair that `flips` or not.
    pub fn adjust(&mut self, j: usize, o: usize, flips: bool) {
        self.flip[j] = self.flip[o] ^ flips;
        self.done[j] = true;
    }

    /// Roots the next part that no pair reached, if any is left.
    pub fn next_root(&mut self) -> Option<usize> {
        while let Some(&r) = self.roots.get(self.next_root) {
            self.next_root += 1;
            let r = r as usize;
            if let (Some(n), false) = (self.normal(r), self.done[r]) {
                self.start(r, faces_away(n, self.c.first_direction));
                return Some(r);
            }
        }
        None
    }
}
