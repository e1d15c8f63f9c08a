//! R*-tree over one tile's points (paper 3 step 1) and exact k-nearest
//! neighbours by the paper's "dynamically expanding hollow sphere" (paper 3
//! step 2, its reference \[6\]): spherical shells of growing radius, each query
//! visiting only the tree nodes that reach into the new shell, until at least
//! `k` points lie inside; then the exact `k` nearest by (dist2, tie key).
//!
//! The [`KnnIndex`] impl is the hollow sphere. On the bench's 1M-point sheet
//! it took 10.5 us of CPU per query single-threaded against 15.4 us for
//! rstar's best-first nearest-neighbour iterator (kept as
//! [`RTreeIndex::knn_best_first`]), and the same wall time with two threads
//! on a loaded machine. Both return identical neighbours; the tests check
//! them against a brute-force oracle. rstar's default node sizes: larger
//! nodes measured no faster.

use glam::DVec3;
use rstar::{PointDistance, RTree, RTreeObject, SelectionFunction, AABB};

use super::{KnnIndex, Neighbour};

/// Radius growth after a shell that found nothing: no density to
/// extrapolate from yet.
const EMPTY_SHELL_GROWTH: f64 = 2.0;
/// Bounds on how much one shell may grow the radius, so that a noisy density
/// estimate can neither stall the search nor jump to the whole tile.
const MIN_SHELL_GROWTH: f64 = 1.25;
const MAX_SHELL_GROWTH: f64 = 4.0;
/// Safety factor on the radius predicted from the density estimate, so that
/// most searches end after their first shell.
const RADIUS_SLACK: f64 = 1.15;
/// How many points the spacing estimate samples.
const SPACING_SAMPLES: usize = 64;

/// Why an index could not be built.
#[derive(Debug, thiserror::Error, PartialEq)]
#[non_exhaustive]
pub enum RTreeError {
    /// The points and the tie keys differ in number.
    #[error("{points} points but {ties} tie keys")]
    LengthMismatch {
        /// Points given.
        points: usize,
        /// Tie keys given.
        ties: usize,
    },
    /// A point has a NaN or infinite coordinate.
    #[error("point {index} has a non-finite coordinate")]
    NonFinite {
        /// Its index.
        index: usize,
    },
    /// More points than u32 indices can name.
    #[error("{len} points do not fit 32-bit point indices")]
    TooManyPoints {
        /// Points given.
        len: usize,
    },
}

/// One tree entry: a point and its position in the indexed slice.
#[derive(Clone, Copy, Debug)]
struct TreePoint {
    pos: [f64; 3],
    index: u32,
}

/// The project's one squared distance (see `spatial`): the tree must rank
/// points by exactly this value, so it is the tree's metric too.
fn dist2(p: [f64; 3], q: [f64; 3]) -> f64 {
    (DVec3::from_array(p) - DVec3::from_array(q)).length_squared()
}

impl RTreeObject for TreePoint {
    type Envelope = AABB<[f64; 3]>;

    fn envelope(&self) -> Self::Envelope {
        AABB::from_point(self.pos)
    }
}

impl PointDistance for TreePoint {
    fn distance_2(&self, q: &[f64; 3]) -> f64 {
        dist2(self.pos, *q)
    }

    fn contains_point(&self, q: &[f64; 3]) -> bool {
        self.pos == *q
    }

    fn distance_2_if_less_or_equal(&self, q: &[f64; 3], max2: f64) -> Option<f64> {
        let d2 = dist2(self.pos, *q);
        (d2 <= max2).then_some(d2)
    }
}

/// Squared distance from `q` to the farthest corner of `env`. Rounding is
/// monotone, so no point inside `env` has a larger [`dist2`]: a node with
/// this bound inside a shell's inner sphere holds no point of the shell.
fn max_dist2(env: &AABB<[f64; 3]>, q: [f64; 3]) -> f64 {
    let q = DVec3::from_array(q);
    let lo = (DVec3::from_array(env.lower()) - q).abs();
    let hi = (DVec3::from_array(env.upper()) - q).abs();
    lo.max(hi).length_squared()
}

/// Selects the points with `inner2 < dist2 <= outer2`: one hollow shell.
/// The envelope's nearest-point distance never exceeds a contained point's
/// [`dist2`] (rounding is monotone), so pruning by it is exact.
struct Shell {
    q: [f64; 3],
    inner2: f64,
    outer2: f64,
}

impl SelectionFunction<TreePoint> for Shell {
    fn should_unpack_parent(&self, env: &AABB<[f64; 3]>) -> bool {
        env.distance_2(&self.q) <= self.outer2 && max_dist2(env, self.q) > self.inner2
    }

    fn should_unpack_leaf(&self, leaf: &TreePoint) -> bool {
        let d2 = leaf.distance_2(&self.q);
        d2 > self.inner2 && d2 <= self.outer2
    }
}

/// An R*-tree over one tile's points, ranking ties by the points' global ids.
pub struct RTreeIndex<'a> {
    tree: RTree<TreePoint>,
    points: &'a [DVec3],
    tie: &'a [u64],
    spacing: f64,
}

impl<'a> RTreeIndex<'a> {
    /// Bulk-loads the tree. `tie[i]` is point `i`'s global id.
    pub fn new(points: &'a [DVec3], tie: &'a [u64]) -> Result<Self, RTreeError> {
        validate(points, tie)?;
        let entries = points
            .iter()
            .zip(0u32..)
            .map(|(p, index)| TreePoint {
                pos: p.to_array(),
                index,
            })
            .collect();
        let tree = RTree::bulk_load(entries);
        let spacing = estimate_spacing(&tree, points);
        Ok(RTreeIndex {
            tree,
            points,
            tie,
            spacing,
        })
    }

    /// The points indexed.
    pub fn points(&self) -> &'a [DVec3] {
        self.points
    }

    /// The tie key of each point (ties in distance go to the smaller key).
    pub fn ties(&self) -> &'a [u64] {
        self.tie
    }

    /// Typical nearest-neighbour distance (from a fixed sample of points),
    /// the density estimate that sizes the first shell.
    pub fn spacing(&self) -> f64 {
        self.spacing
    }

    /// The paper's kNN: clears `out`, then fills it with the `k` nearest
    /// points to `q` (skipping `exclude`) sorted by (dist2, tie key), found by
    /// expanding hollow shells. A non-finite `q` has no neighbours.
    pub fn knn_hollow(&self, q: DVec3, k: usize, exclude: Option<u32>, out: &mut Vec<Neighbour>) {
        out.clear();
        let want = k.min(self.len() - usize::from(self.holds(exclude)));
        if want == 0 || !q.is_finite() {
            return;
        }
        let q = q.to_array();
        let mut inner2 = f64::NEG_INFINITY;
        let mut radius = self.first_radius(want);
        loop {
            let outer2 = radius * radius;
            let shell = Shell { q, inner2, outer2 };
            for p in self.tree.locate_with_selection_function(shell) {
                if Some(p.index) != exclude {
                    out.push(Neighbour {
                        dist2: dist2(p.pos, q),
                        index: p.index,
                    });
                }
            }
            // Every point with dist2 <= outer2 is in `out` (the shells tile
            // [0, outer2]), so the `want` nearest, ties included, are too.
            if out.len() >= want {
                break;
            }
            inner2 = outer2;
            radius *= shell_growth(out.len(), want);
        }
        self.sort_and_truncate(out, want);
    }

    /// The same answer as [`Self::knn_hollow`] through rstar's best-first
    /// iterator, which yields points in nondecreasing `dist2`: read on past
    /// the `k`-th point while the distance ties it, then order ties by key.
    pub fn knn_best_first(
        &self,
        q: DVec3,
        k: usize,
        exclude: Option<u32>,
        out: &mut Vec<Neighbour>,
    ) {
        out.clear();
        if k == 0 || !q.is_finite() {
            return;
        }
        for (p, d2) in self
            .tree
            .nearest_neighbor_iter_with_distance_2(q.to_array())
        {
            if Some(p.index) == exclude {
                continue;
            }
            if out.len() >= k && out.last().is_some_and(|last| d2 > last.dist2) {
                break;
            }
            out.push(Neighbour {
                dist2: d2,
                index: p.index,
            });
        }
        self.sort_and_truncate(out, k);
    }

    fn holds(&self, exclude: Option<u32>) -> bool {
        exclude.is_some_and(|i| (i as usize) < self.len())
    }

    /// Radius expected to hold `want` points on a surface sampled at
    /// `spacing` (`want ~ pi r^2 / spacing^2`), with some slack.
    fn first_radius(&self, want: usize) -> f64 {
        self.spacing * (want as f64 / std::f64::consts::PI).sqrt() * RADIUS_SLACK
    }

    fn sort_and_truncate(&self, out: &mut Vec<Neighbour>, k: usize) {
        let tie = self.tie;
        out.sort_unstable_by(|a, b| {
            a.dist2
                .total_cmp(&b.dist2)
                .then(tie[a.index as usize].cmp(&tie[b.index as usize]))
                .then(a.index.cmp(&b.index))
        });
        out.truncate(k);
    }
}

/// Factor for the next shell's radius after `found < want` points: the
/// surface density seen so far predicts the radius holding `want`.
fn shell_growth(found: usize, want: usize) -> f64 {
    if found == 0 {
        return EMPTY_SHELL_GROWTH;
    }
    let predicted = (want as f64 / found as f64).sqrt() * RADIUS_SLACK;
    predicted.clamp(MIN_SHELL_GROWTH, MAX_SHELL_GROWTH)
}

impl KnnIndex for RTreeIndex<'_> {
    fn knn(&self, q: DVec3, k: usize, exclude: Option<u32>, out: &mut Vec<Neighbour>) {
        self.knn_hollow(q, k, exclude, out);
    }

    fn len(&self) -> usize {
        self.points.len()
    }
}

fn validate(points: &[DVec3], tie: &[u64]) -> Result<(), RTreeError> {
    if points.len() != tie.len() {
        return Err(RTreeError::LengthMismatch {
            points: points.len(),
            ties: tie.len(),
        });
    }
    if u32::try_from(points.len()).is_err() {
        return Err(RTreeError::TooManyPoints { len: points.len() });
    }
    match points.iter().position(|p| !p.is_finite()) {
        Some(index) => Err(RTreeError::NonFinite { index }),
        None => Ok(()),
    }
}

/// Median distance from a fixed sample of points to their nearest other
/// point at a positive distance. Falls back to a surface-like estimate from
/// the bounding box, and to 1 when every point coincides; any positive value
/// keeps the hollow-sphere search exact, only its speed depends on it.
fn estimate_spacing(tree: &RTree<TreePoint>, points: &[DVec3]) -> f64 {
    let step = (points.len() / SPACING_SAMPLES).max(1);
    let mut nearest: Vec<f64> = points
        .iter()
        .step_by(step)
        .filter_map(|p| {
            tree.nearest_neighbor_iter_with_distance_2(p.to_array())
                .map(|(_, d2)| d2)
                .find(|&d2| d2 > 0.0)
        })
        .map(f64::sqrt)
        .collect();
    nearest.sort_unstable_by(f64::total_cmp);
    if let Some(&median) = nearest.get(nearest.len() / 2) {
        if median > 0.0 && median.is_finite() {
            return median;
        }
    }
    let extent = tree.root().envelope().upper();
    let lower = tree.root().envelope().lower();
    let diagonal = (DVec3::from_array(extent) - DVec3::from_array(lower)).length();
    let fallback = diagonal / (points.len().max(1) as f64).sqrt();
    if fallback > 0.0 && fallback.is_finite() {
        fallback
    } else {
        1.0
    }
}
