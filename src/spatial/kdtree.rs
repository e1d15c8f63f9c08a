//! Exact kNN through kiddo's immutable kd-tree (an alternative to the uniform
//! grid of paper 1 section 2.1, same answers).
//!
//! kiddo returns equidistant points in arbitrary order and computes distances
//! its own way, so its answer is only a candidate set: we ask for one more
//! point than needed, recompute every squared distance with the canonical
//! formula, sort by (dist2, tie key) and accept when the farthest point kiddo
//! returned is clearly beyond the k-th. Otherwise (ties at the boundary,
//! duplicates) we ask again for twice as many.

use std::num::NonZeroUsize;

use glam::DVec3;
use kiddo::{kd_tree::KdTree, Eytzinger, SquaredEuclidean, VecOfArenas};

use super::brute::{dist2, neighbour_order};
use super::{check_input, IndexError, KnnIndex, Neighbour};

/// Relative gap between kiddo's farthest returned distance and our k-th
/// distance that proves no unreturned point can sort before the k-th. It
/// dwarfs the few-ulp difference between two evaluations of a squared
/// distance, whatever the summation order or vector width.
const ROUNDING_GAP: f64 = 1e-12;

/// Points per leaf. kiddo's `ImmutableKdTree` alias uses 32; 8 ran ~12 %
/// fewer instructions per k = 12 query (callgrind, 1M-point sphere). The
/// immutable layout accepts any number of identical points whatever the
/// bucket size (tests/knn_oracle.rs puts ~150 on one spot).
const BUCKET: usize = 8;

/// kiddo's immutable kd-tree layout (as `kiddo::ImmutableKdTree`) with our
/// bucket size: items are `u32` indices into the borrowed points.
type Tree = KdTree<f64, u32, Eytzinger, VecOfArenas<f64, u32, 3, BUCKET>, 3, BUCKET>;

/// kd-tree exact kNN index over borrowed points.
pub struct KdIndex<'a> {
    tree: Tree,
    points: &'a [DVec3],
    tie: &'a [u64],
}

impl<'a> KdIndex<'a> {
    /// Builds the tree (in parallel above kiddo's size threshold). Items are
    /// the points' indices in `points`.
    pub fn new(points: &'a [DVec3], tie: &'a [u64]) -> Result<Self, IndexError> {
        check_input(points, tie)?;
        let tree = Tree::new_from_source(
            points,
            |p: &DVec3, axis| p.to_array()[axis.min(2)],
            |i, _| i as u32,
        )?;
        Ok(KdIndex { tree, points, tie })
    }

    /// Runs one kiddo query for `m` candidates; fills `out` with the
    /// non-excluded ones under the canonical distance, sorted. Returns how
    /// many kiddo returned and kiddo's largest distance among them.
    fn candidates(
        &self,
        q: DVec3,
        m: NonZeroUsize,
        exclude: Option<u32>,
        out: &mut Vec<Neighbour>,
    ) -> (usize, f64) {
        let found = self
            .tree
            .query(&q.to_array())
            .nearest_n::<SquaredEuclidean<f64>>(m)
            .unsorted()
            .execute();
        out.clear();
        let mut farthest = 0.0f64;
        for r in &found {
            farthest = farthest.max(r.distance);
            if Some(r.item) == exclude {
                continue;
            }
            if let Some(p) = self.points.get(r.item as usize) {
                out.push(Neighbour {
                    dist2: dist2(*p, q),
                    index: r.item,
                });
            }
        }
        out.sort_unstable_by(|a, b| neighbour_order(self.tie, a, b));
        (found.len(), farthest)
    }
}

impl KdIndex<'_> {
    /// The single nearest point, exactly (ties by key), for the commonest
    /// query of marching cubes: kiddo's two nearest settle it when the second
    /// is clearly farther (no tie is possible, whatever the rounding of the
    /// two distance formulas); otherwise the general path sorts it out.
    /// One traversal: the former `nearest_one` plus a tie-ball `within`
    /// query took 1.5x the instructions (callgrind, 200k dragon corners).
    fn nearest(&self, q: DVec3, out: &mut Vec<Neighbour>) {
        let found = self
            .tree
            .query(&q.to_array())
            .nearest_n::<SquaredEuclidean<f64>>(NonZeroUsize::MIN.saturating_add(1))
            .unsorted()
            .execute();
        if let [a, b] = found[..] {
            let (first, second) = if a.distance <= b.distance {
                (a, b)
            } else {
                (b, a)
            };
            if first.distance * (1.0 + 4.0 * ROUNDING_GAP) < second.distance {
                if let Some(p) = self.points.get(first.item as usize) {
                    out.push(Neighbour {
                        dist2: dist2(*p, q),
                        index: first.item,
                    });
                    return;
                }
            }
        }
        self.general(q, 1, None, out);
    }

    /// Any k >= 1: kiddo's candidates under the canonical order, asked again
    /// for twice as many until the k-th is clearly inside what kiddo
    /// returned.
    fn general(&self, q: DVec3, k: usize, exclude: Option<u32>, out: &mut Vec<Neighbour>) {
        let n = self.points.len();
        let excluded = exclude.is_some_and(|e| (e as usize) < n) as usize;
        let mut want = k.saturating_add(excluded + 1).min(n);
        while let Some(m) = NonZeroUsize::new(want) {
            let (returned, farthest) = self.candidates(q, m, exclude, out);
            let all_seen = returned >= n;
            let beyond_kth = out
                .get(k - 1)
                .is_some_and(|kth| kth.dist2 * (1.0 + ROUNDING_GAP) < farthest);
            if all_seen || beyond_kth || want == n {
                break;
            }
            want = want.saturating_mul(2).min(n);
        }
        out.truncate(k);
    }
}

impl KnnIndex for KdIndex<'_> {
    fn knn(&self, q: DVec3, k: usize, exclude: Option<u32>, out: &mut Vec<Neighbour>) {
        out.clear();
        let n = self.points.len();
        if k == 0 || n == 0 {
            return;
        }
        if k == 1 && exclude.is_none() {
            return self.nearest(q, out);
        }
        self.general(q, k, exclude, out);
    }

    fn len(&self) -> usize {
        self.points.len()
    }
}
