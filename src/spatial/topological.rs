//! Topological neighbours by mean reverse shift (paper 3, Sun et al. 2015):
//! the k nearest neighbours crowd to the dense side of a density change; the
//! mean of the neighbourhood points that way, so a kNN query mirrored to the
//! other side of the point fetches the missing sparse-side neighbours.
//!
//! Per point O (paper 3 steps 2-5, section 2.2 of the original):
//! 1. `T = kNN(O)`, O itself excluded (the paper queries "the k neighbours of
//!    O"; O is not its own neighbour).
//! 2. Bandwidth `h = r_min`, the radius of the smallest sphere around O that
//!    holds this initial `T` (the k-th distance). The original fixes h from
//!    the k-neighbour data ("最终包含样点所有k邻域数据的最小空心球半径"), so
//!    h is *not* re-grown with `T`.
//! 3. Mean at O over T, eq. (3): `m = sum x_i g(|O-x_i|^2/h^2) / sum g(..)`,
//!    `M = m - O`. The original leaves the kernel open ("给定核函数g(x)");
//!    we use the normal kernel's profile `g(u) = exp(-u/2)` (Comaniciu & Meer,
//!    its reference \[13\]). Deviation, named: with the flat `g` of the
//!    Epanechnikov kernel every point found after step 1 lies beyond h and
//!    weighs 0, so the iteration could never move past its first shift.
//! 4. Reverse shift `X = O - M`, query `kNN(X)` (k points, O excluded).
//! 5. If the query found points not yet in T, add them and go to 3 (the mean
//!    is re-evaluated at O, as in the original step (3)); otherwise stop.
//!    Iterations are capped (`TopoParams::max_iterations`) and the cap is
//!    reported.

use glam::DVec3;
use rayon::prelude::*;

use super::rtree::RTreeIndex;
use super::{KnnIndex, Neighbour};

/// Parameters of the mean reverse shift (paper 3 step 6).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TopoParams {
    /// Points per kNN query; the paper recommends 8..30, usually 15.
    pub k: usize,
    /// Cap on reverse-shift queries that add points (the paper sees 0..4).
    /// With 0, T is plain kNN and `hit_cap` is set (convergence unchecked).
    pub max_iterations: usize,
}

impl Default for TopoParams {
    fn default() -> Self {
        TopoParams {
            k: 15,
            max_iterations: 10,
        }
    }
}

/// The topological neighbourhood of one point.
#[derive(Clone, Debug, PartialEq)]
pub struct TopoResult {
    /// T, sorted by (dist2 from O, tie key).
    pub neighbours: Vec<Neighbour>,
    /// Reverse-shift queries that added points (the paper's c).
    pub iterations: u32,
    /// The cap stopped the iteration while queries still added points.
    pub hit_cap: bool,
    /// Largest distance from O of any point the queries could have needed:
    /// the max over queries of |X - O| + that query's k-th distance. A tile
    /// margin of at least `reach` around O gives the untiled result.
    /// Rounded up slightly; infinite when a query found fewer than k points
    /// (it needed them all).
    pub reach: f64,
}

/// Why a query was refused.
#[derive(Debug, thiserror::Error, PartialEq)]
#[non_exhaustive]
pub enum TopoError {
    /// The points or tie keys given are not those the index was built over.
    #[error("index holds {index} points but {points} points and {ties} tie keys were given")]
    IndexMismatch {
        /// Points the index holds.
        index: usize,
        /// Points given.
        points: usize,
        /// Tie keys given.
        ties: usize,
    },
    /// A query names a point the index does not hold.
    #[error("point {point} out of range ({len} points)")]
    PointOutOfRange {
        /// The point.
        point: u32,
        /// Points the index holds.
        len: usize,
    },
}

/// Reusable buffers, one per worker, so the per-point loop only allocates
/// its result.
#[derive(Debug, Default)]
pub struct TopoScratch {
    query: Vec<Neighbour>,
    members: Vec<u32>,
}

impl TopoScratch {
    /// Empty buffers.
    pub fn new() -> Self {
        Self::default()
    }
}

/// Topological neighbours of point `i` (paper 3). `points` and `tie` must be
/// the slices `index` was built over.
pub fn topological_neighbours(
    index: &RTreeIndex,
    points: &[DVec3],
    tie: &[u64],
    i: u32,
    params: &TopoParams,
    scratch: &mut TopoScratch,
) -> Result<TopoResult, TopoError> {
    check_inputs(index, points, tie)?;
    if i as usize >= points.len() {
        return Err(TopoError::PointOutOfRange {
            point: i,
            len: points.len(),
        });
    }
    Ok(reverse_shift(index, points, tie, i, params, scratch))
}

/// Topological neighbours of every point, in point order, with rayon. Each
/// result depends only on its point, so the output is the same for any
/// thread count.
pub fn all_topological(
    index: &RTreeIndex,
    points: &[DVec3],
    tie: &[u64],
    params: &TopoParams,
) -> Result<Vec<TopoResult>, TopoError> {
    check_inputs(index, points, tie)?;
    // The index holds at most u32::MAX points (checked when it was built).
    let len = u32::try_from(points.len()).unwrap_or(u32::MAX);
    Ok((0..len)
        .into_par_iter()
        .map_init(TopoScratch::new, |scratch, i| {
            reverse_shift(index, points, tie, i, params, scratch)
        })
        .collect())
}

fn check_inputs(index: &RTreeIndex, points: &[DVec3], tie: &[u64]) -> Result<(), TopoError> {
    if index.len() == points.len() && index.len() == tie.len() {
        Ok(())
    } else {
        Err(TopoError::IndexMismatch {
            index: index.len(),
            points: points.len(),
            ties: tie.len(),
        })
    }
}

/// Steps 1-5 for one point; `i` is in range.
fn reverse_shift(
    index: &RTreeIndex,
    points: &[DVec3],
    tie: &[u64],
    i: u32,
    params: &TopoParams,
    scratch: &mut TopoScratch,
) -> TopoResult {
    let o = points[i as usize];
    let k = params.k;
    let TopoScratch { query, members } = scratch;
    index.knn_hollow(o, k, Some(i), query);
    let mut reach = query_reach(0.0, query, k);
    let h2 = query.last().map_or(0.0, |n| n.dist2);
    members.clear();
    members.extend(query.iter().map(|n| n.index));
    let mut iterations = 0u32;
    let mut hit_cap = false;
    loop {
        if iterations as usize >= params.max_iterations {
            hit_cap = true;
            break;
        }
        let x = o - mean_shift(o, members, points, h2);
        if x == o {
            break; // kNN(X) would repeat step 1
        }
        index.knn_hollow(x, k, Some(i), query);
        reach = reach.max(query_reach((x - o).length(), query, k));
        if add_new(members, query) == 0 {
            break;
        }
        iterations += 1;
    }
    TopoResult {
        neighbours: sorted_members(members, points, tie, o),
        iterations,
        hit_cap,
        reach,
    }
}

/// Relative round-up of `reach`, so that testing a point's float distance
/// against it never drops a point the exact bound includes.
const REACH_ROUND_UP: f64 = 1.0 + 1e-12;

/// |X - O| plus the query's k-th distance, rounded up; infinite for a short
/// answer.
fn query_reach(shift: f64, found: &[Neighbour], k: usize) -> f64 {
    match found.last() {
        Some(last) if found.len() >= k => (shift + last.dist2.sqrt()) * REACH_ROUND_UP,
        _ if k == 0 => shift,
        _ => f64::INFINITY,
    }
}

/// `M(O) = m(O) - O`, eq. (2)-(3), summed relative to O for precision.
/// Zero when h is zero (every neighbour coincides with O).
fn mean_shift(o: DVec3, members: &[u32], points: &[DVec3], h2: f64) -> DVec3 {
    if h2.is_nan() || h2 <= 0.0 {
        return DVec3::ZERO;
    }
    let mut weighted = DVec3::ZERO;
    let mut total = 0.0;
    for &m in members {
        let d = points[m as usize] - o;
        let w = kernel_profile(d.length_squared() / h2);
        weighted += d * w;
        total += w;
    }
    if total > 0.0 {
        weighted / total
    } else {
        DVec3::ZERO
    }
}

/// Profile of the normal kernel, `g(u) = exp(-u/2)` (constant factor dropped:
/// it cancels in the mean).
fn kernel_profile(u: f64) -> f64 {
    (-0.5 * u).exp()
}

/// Appends the query's points not yet in T; returns how many were new.
fn add_new(members: &mut Vec<u32>, found: &[Neighbour]) -> usize {
    let before = members.len();
    for n in found {
        if !members[..before].contains(&n.index) {
            members.push(n.index);
        }
    }
    members.len() - before
}

fn sorted_members(members: &[u32], points: &[DVec3], tie: &[u64], o: DVec3) -> Vec<Neighbour> {
    let mut out: Vec<Neighbour> = members
        .iter()
        .map(|&m| Neighbour {
            dist2: (points[m as usize] - o).length_squared(),
            index: m,
        })
        .collect();
    out.sort_unstable_by(|a, b| {
        a.dist2
            .total_cmp(&b.dist2)
            .then(tie[a.index as usize].cmp(&tie[b.index as usize]))
            .then(a.index.cmp(&b.index))
    });
    out
}
