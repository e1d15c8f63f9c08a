//! One grid query's candidates: the caller's `out`, holding the best `k`
//! found so far in the canonical order (insertion from the end: k is small).

use glam::DVec3;

use crate::spatial::brute::{dist2, neighbour_order};
use crate::spatial::Neighbour;

pub(super) struct Search<'o> {
    pub(super) q: DVec3,
    k: usize,
    exclude: Option<u32>,
    tie: &'o [u64],
    out: &'o mut Vec<Neighbour>,
    /// Squared distance of the k-th best candidate so far; infinite until
    /// `k` candidates were seen. Only ever decreases.
    pub(super) bound: f64,
    /// Rounding allowance (a distance), see `GridIndex::tolerance`.
    pub(super) tol: f64,
}

impl<'o> Search<'o> {
    pub(super) fn new(
        q: DVec3,
        k: usize,
        exclude: Option<u32>,
        tie: &'o [u64],
        tol: f64,
        out: &'o mut Vec<Neighbour>,
    ) -> Self {
        out.clear();
        Search {
            q,
            k,
            exclude,
            tie,
            out,
            bound: f64::INFINITY,
            tol,
        }
    }

    /// Offers the points `pts` (with original indices `ids`): the hot loop,
    /// which only computes distances until one can qualify.
    #[inline]
    pub(super) fn offer_all(&mut self, pts: &[DVec3], ids: &[u32]) {
        let q = self.q;
        let mut bound = self.bound;
        for (p, &index) in pts.iter().zip(ids) {
            let d2 = dist2(*p, q);
            if d2 <= bound {
                bound = self.insert(Neighbour { dist2: d2, index });
            }
        }
    }

    /// Inserts a candidate no farther than the bound in order, if it is among
    /// the best `k`; returns the new bound.
    #[inline]
    fn insert(&mut self, cand: Neighbour) -> f64 {
        if Some(cand.index) == self.exclude {
            return self.bound;
        }
        let tie = self.tie;
        let out = &mut *self.out;
        if out.len() >= self.k {
            match out.last() {
                Some(last) if goes_before(tie, &cand, last) => out.truncate(self.k - 1),
                _ => return self.bound,
            }
        }
        // Insertion-sort step, shifting by hand: k is small.
        out.push(cand);
        let v = out.as_mut_slice();
        let mut at = v.len() - 1;
        while at > 0 {
            let prev = v[at - 1];
            if !goes_before(tie, &cand, &prev) {
                break;
            }
            v[at] = prev;
            at -= 1;
        }
        v[at] = cand;
        if v.len() == self.k {
            self.bound = v[v.len() - 1].dist2;
        }
        self.bound
    }

    /// The bound used to skip cells, inflated by a relative 16 ulps so that a
    /// skipped point's computed squared distance is strictly beyond `bound`.
    pub(super) fn pruning_bound(&self) -> f64 {
        self.bound * (1.0 + 16.0 * f64::EPSILON)
    }

    pub(super) fn is_full(&self) -> bool {
        self.out.len() == self.k
    }

    /// Forgets all candidates (before a full scan).
    pub(super) fn restart(&mut self) {
        self.out.clear();
        self.bound = f64::INFINITY;
    }
}

/// `a` sorts before `b`; the tie keys are read only on equal distances.
#[inline]
fn goes_before(tie: &[u64], a: &Neighbour, b: &Neighbour) -> bool {
    a.dist2 < b.dist2 || (a.dist2 == b.dist2 && neighbour_order(tie, a, b).is_lt())
}
