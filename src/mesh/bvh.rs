//! Bounding-volume hierarchy for exact nearest-primitive queries (points or
//! triangles): axis-aligned boxes, split at the median centroid along the
//! longest axis (the classic object-median BVH; Ericson, "Real-Time
//! Collision Detection", section 6.2), searched depth-first, nearer child
//! first, pruning a box only when its distance exceeds the best found.
//!
//! Deviation from the brief's suggestion (rstar with triangle boxes, which
//! this module first used): measured here on a 490k-triangle torus, rstar's
//! nearest query cost about 5 us of CPU and its build about 1 us per
//! triangle; this flat tree, primitives stored in leaf order, took about
//! 1.3 us per query (same machine, same load) and builds in parallel. Its
//! pruning (box distance > best) is a pure lower bound, with no min-max
//! heuristic that rounding could trip. Same envelope idea, so the
//! exactness argument is unchanged.
//!
//! Exact: the result is the minimum of `distance2` over every primitive
//! (boxes are the exact min/max of the primitive's coordinates, so a box is
//! never farther than anything inside it). Deterministic: the build sorts
//! by (centroid coordinate, input index).

use glam::DVec3;
use rayon::prelude::*;

/// Something with a box and an exact squared distance to a point.
pub(crate) trait Primitive: Send + Sync {
    fn bounds(&self) -> (DVec3, DVec3);
    fn distance2(&self, p: DVec3) -> f64;
}

/// Primitives per leaf at most: median splits leave 5..=8, a good balance
/// between node count (about 19 bytes per primitive) and leaf scans.
const LEAF: usize = 8;
/// Median splits halve every range, so depth <= log2(2^32 / 1) + 1 and the
/// traversal stack never holds more than one entry per level plus one.
const STACK: usize = 72;

#[derive(Clone, Copy, Debug)]
struct Node {
    min: DVec3,
    max: DVec3,
    /// Leaf: first primitive; inner: index of the left child (right = +1).
    first: u32,
    /// Leaf: number of primitives (> 0); inner: 0.
    count: u32,
}

impl Node {
    fn distance2(&self, p: DVec3) -> f64 {
        (self.min - p)
            .max(p - self.max)
            .max(DVec3::ZERO)
            .length_squared()
    }
}

pub(crate) struct Bvh<P> {
    nodes: Vec<Node>,
    /// Primitives in leaf order.
    prims: Vec<P>,
    /// Input index of each primitive in `prims`.
    ids: Vec<u32>,
}

impl<P: Primitive> Bvh<P> {
    /// Builds over `n` primitives (`n <= u32::MAX`, callers check) given
    /// by `bounds_of(i)` and made by `make(i)` once their leaf order is
    /// known, so they are written once, in order, and never moved. While
    /// building, a compact (centre, id) list takes 32 B per primitive.
    pub fn build(
        n: usize,
        bounds_of: impl Fn(u32) -> (DVec3, DVec3) + Sync,
        make: impl Fn(u32) -> P + Sync,
    ) -> Self {
        let mut items: Vec<(DVec3, u32)> = (0..n as u32)
            .into_par_iter()
            .map(|i| {
                let (lo, hi) = bounds_of(i);
                (lo + hi, i)
            })
            .collect();
        let mut nodes = Vec::with_capacity(n / 3 + 1);
        if n > 0 {
            nodes.push(Node {
                min: DVec3::ZERO,
                max: DVec3::ZERO,
                first: 0,
                count: n as u32,
            });
            split_all(&mut nodes, &mut items);
        }
        let ids: Vec<u32> = items.iter().map(|&(_, id)| id).collect();
        drop(items);
        let prims: Vec<P> = ids.par_iter().map(|&i| make(i)).collect();
        fit_bounds(&mut nodes, &prims);
        Bvh { nodes, prims, ids }
    }

    pub fn len(&self) -> usize {
        self.prims.len()
    }

    /// Smallest squared distance from `p` to a primitive whose input index
    /// is not `exclude`; infinite when there is none.
    pub fn nearest_distance2(&self, p: DVec3, exclude: Option<u32>) -> f64 {
        let mut best = f64::INFINITY;
        if self.nodes.is_empty() {
            return best;
        }
        let mut stack = [0u32; STACK];
        let mut len = 1;
        while len > 0 {
            len -= 1;
            let node = &self.nodes[stack[len] as usize];
            if node.distance2(p) > best {
                continue;
            }
            if node.count > 0 {
                let range = node.first as usize..(node.first + node.count) as usize;
                for (prim, &id) in self.prims[range.clone()].iter().zip(&self.ids[range]) {
                    if Some(id) != exclude {
                        best = best.min(prim.distance2(p));
                    }
                }
                continue;
            }
            let (l, r) = (node.first, node.first + 1);
            let dl = self.nodes[l as usize].distance2(p);
            let dr = self.nodes[r as usize].distance2(p);
            // Push the farther child first so the nearer one is searched
            // first and tightens `best` early.
            let (near, far, d_far) = if dl <= dr { (l, r, dr) } else { (r, l, dl) };
            if d_far <= best {
                stack[len] = far;
                len += 1;
            }
            stack[len] = near;
            len += 1;
        }
        best
    }

    /// Calls `visit(id, prim)` for every primitive whose box meets the
    /// closed box `[lo, hi]`, in leaf order.
    pub fn for_each_overlapping(&self, lo: DVec3, hi: DVec3, mut visit: impl FnMut(u32, &P)) {
        let meets = |min: DVec3, max: DVec3| min.cmple(hi).all() && lo.cmple(max).all();
        if self.nodes.is_empty() {
            return;
        }
        let mut stack = [0u32; STACK];
        let mut len = 1;
        while len > 0 {
            len -= 1;
            let node = &self.nodes[stack[len] as usize];
            if !meets(node.min, node.max) {
                continue;
            }
            if node.count == 0 {
                stack[len] = node.first;
                stack[len + 1] = node.first + 1;
                len += 2;
                continue;
            }
            let range = node.first as usize..(node.first + node.count) as usize;
            for (prim, &id) in self.prims[range.clone()].iter().zip(&self.ids[range]) {
                let (min, max) = prim.bounds();
                if meets(min, max) {
                    visit(id, prim);
                }
            }
        }
    }
}

/// Splits every node larger than [`LEAF`] at the median of its centres
/// along their longest axis, one level at a time: the nodes of a level own
/// disjoint ranges of `items`, so they are split in parallel; children are
/// appended in level order, after their parent. Ties are broken by id, so
/// the tree does not depend on the thread count.
fn split_all(nodes: &mut Vec<Node>, items: &mut [(DVec3, u32)]) {
    let mut level: Vec<usize> = vec![0];
    while !level.is_empty() {
        let mut ranges = level_ranges(nodes, &level, items);
        ranges
            .par_iter_mut()
            .filter(|r| r.len() > LEAF)
            .for_each(|r| median_split(r));
        let mut next = Vec::new();
        for &k in &level {
            let (first, count) = (nodes[k].first as usize, nodes[k].count as usize);
            if count <= LEAF {
                continue;
            }
            let half = count / 2;
            let child = |first: usize, count: usize| Node {
                min: DVec3::ZERO,
                max: DVec3::ZERO,
                first: first as u32,
                count: count as u32,
            };
            next.extend([nodes.len(), nodes.len() + 1]);
            nodes[k].first = nodes.len() as u32;
            nodes[k].count = 0;
            nodes.extend([child(first, half), child(first + half, count - half)]);
        }
        level = next;
    }
}

/// The item ranges of `level`'s nodes, which are disjoint and in order.
fn level_ranges<'a>(
    nodes: &[Node],
    level: &[usize],
    items: &'a mut [(DVec3, u32)],
) -> Vec<&'a mut [(DVec3, u32)]> {
    let mut out = Vec::with_capacity(level.len());
    let mut rest = items;
    let mut offset = 0;
    for &k in level {
        let (first, count) = (nodes[k].first as usize, nodes[k].count as usize);
        let (_, tail) = std::mem::take(&mut rest).split_at_mut(first - offset);
        let (mine, tail) = tail.split_at_mut(count);
        out.push(mine);
        rest = tail;
        offset = first + count;
    }
    out
}

fn median_split(range: &mut [(DVec3, u32)]) {
    let axis = longest_axis(range);
    range.select_nth_unstable_by(range.len() / 2, |a, b| {
        a.0[axis].total_cmp(&b.0[axis]).then(a.1.cmp(&b.1))
    });
}

/// The axis along which the centres spread most.
fn longest_axis(range: &[(DVec3, u32)]) -> usize {
    let (mut min, mut max) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    for &(c, _) in range.iter() {
        min = min.min(c);
        max = max.max(c);
    }
    let e = max - min;
    if e.x >= e.y && e.x >= e.z {
        0
    } else if e.y >= e.z {
        1
    } else {
        2
    }
}

/// Boxes bottom-up: leaves from their (now contiguous) primitives, inner
/// nodes from their children, which sit later in `nodes`.
fn fit_bounds<P: Primitive>(nodes: &mut [Node], prims: &[P]) {
    for k in (0..nodes.len()).rev() {
        let node = nodes[k];
        let (min, max) = if node.count > 0 {
            let range = node.first as usize..(node.first + node.count) as usize;
            prims[range].iter().map(Primitive::bounds).fold(
                (DVec3::INFINITY, DVec3::NEG_INFINITY),
                |(a, b), (lo, hi)| (a.min(lo), b.max(hi)),
            )
        } else {
            let (l, r) = (nodes[node.first as usize], nodes[node.first as usize + 1]);
            (l.min.min(r.min), l.max.max(r.max))
        };
        nodes[k].min = min;
        nodes[k].max = max;
    }
}

impl Primitive for DVec3 {
    fn bounds(&self) -> (DVec3, DVec3) {
        (*self, *self)
    }
    fn distance2(&self, p: DVec3) -> f64 {
        (*self - p).length_squared()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearest_point_matches_a_scan_with_and_without_exclusion() {
        let pts: Vec<DVec3> = (0..500u32)
            .map(|i| {
                let f = |k: u32| (i.wrapping_mul(2654435761).rotate_left(k) % 1000) as f64 / 1000.0;
                DVec3::new(f(0), f(11), f(23))
            })
            .collect();
        let bvh = Bvh::build(pts.len(), |i| pts[i as usize].bounds(), |i| pts[i as usize]);
        for (i, &q) in pts.iter().enumerate().step_by(7) {
            let scan = |skip: Option<usize>| {
                pts.iter()
                    .enumerate()
                    .filter(|(j, _)| Some(*j) != skip)
                    .map(|(_, p)| (*p - q).length_squared())
                    .fold(f64::INFINITY, f64::min)
            };
            assert_eq!(bvh.nearest_distance2(q, None), scan(None));
            assert_eq!(bvh.nearest_distance2(q, Some(i as u32)), scan(Some(i)));
        }
        let empty = Bvh::<DVec3>::build(0, |_| (DVec3::ZERO, DVec3::ZERO), |_| DVec3::ZERO);
        assert_eq!(empty.nearest_distance2(DVec3::ZERO, None), f64::INFINITY);
    }
}
