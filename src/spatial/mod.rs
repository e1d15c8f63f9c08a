//! Spatial queries over one tile's points: exact k-nearest neighbours by a
//! uniform grid (paper 1 section 2.1) or a kd-tree (kiddo), every point
//! within a radius (`ball`), a brute-force oracle for tests, and the
//! spacing of a stream of points (`patches`).
//!
//! Every backend returns the same answer bit for bit: neighbours sorted by
//! (squared distance, tie key), where the squared distance is always computed
//! as `(points[i] - q).length_squared()` in f64 and the tie key is the point's
//! global id (its original input index). That is what makes tiled runs equal
//! untiled ones.

use glam::DVec3;

/// Mean nearest-neighbour distance among `points` (exact duplicates left
/// out: a zero distance says nothing of the sampling); `None` with fewer
/// than two distinct points. `scanmesh info`'s estimate over a short
/// file (`patches` measures a long one).
pub fn mean_nearest_distance(points: &[DVec3]) -> Option<f64> {
    let origin = points.first().copied()?;
    let pts: Vec<DVec3> = points.iter().map(|p| *p - origin).collect();
    let ids: Vec<u64> = (0..pts.len() as u64).collect();
    // Fails only past u32::MAX points: no estimate then.
    let index = build_index(KnnBackend::KdTree, &pts, &ids).ok()?;
    let mut nbrs = Vec::new();
    let (mut sum, mut n) = (0.0, 0u64);
    for (i, p) in pts.iter().enumerate() {
        index.knn(*p, 1, Some(i as u32), &mut nbrs);
        if let Some(nb) = nbrs.first().filter(|nb| nb.dist2 > 0.0) {
            sum += nb.dist2.sqrt();
            n += 1;
        }
    }
    (n > 0).then(|| sum / n as f64)
}

pub(crate) mod ball;
pub(crate) mod blocks;
pub(crate) mod brute;
pub(crate) mod grid;
mod kdtree;
pub mod patches;
pub mod rtree;
pub mod topological;

pub(crate) use ball::{key_runs, BallGrid};
pub use brute::{brute_knn, neighbour_order};
pub use grid::GridIndex;
pub use kdtree::KdIndex;

/// One neighbour: its position in the slice the index was built over.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Neighbour {
    /// Squared distance to the query.
    pub dist2: f64,
    /// Index of the point in the slice the index was built over.
    pub index: u32,
}

/// Exact k-nearest-neighbour search over a fixed set of points.
pub trait KnnIndex: Sync {
    /// Clears `out`, then fills it with the `k` nearest points to `q`
    /// (fewer if the index holds fewer), skipping the point at `exclude`,
    /// sorted by (dist2, tie key). Exact: never an approximation.
    fn knn(&self, q: DVec3, k: usize, exclude: Option<u32>, out: &mut Vec<Neighbour>);
    /// Points indexed.
    fn len(&self) -> usize;
    /// Whether the index holds no point.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// Which neighbourhood a per-point computation uses, by kind (the CLI's
/// `--neighbours` of `neighbors`, `normals` and `reconstruct`); the
/// computation's parameters say how many and how far.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum HoodKind {
    /// Paper 3's topological neighbours: mean reverse shift over an R*-tree.
    Topological,
    /// The plain k nearest neighbours.
    Knn,
}

/// Which kNN structure to build. The grid is the default: on 1M-point
/// surfaces it answered k = 12 queries in about 5,400 instructions against
/// the kd-tree's 9,100 (callgrind), and the normals pipeline ran faster and
/// in less memory with it (benches/knn.rs, benches/normals.rs).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum KnnBackend {
    /// Uniform grid with a search that widens until the k-th distance lies
    /// inside the searched block.
    #[default]
    #[value(help = None::<&str>)]
    Grid,
    /// kiddo's immutable kd-tree, asked for extra neighbours to settle ties.
    #[value(name = "kdtree", help = None::<&str>)]
    KdTree,
}

/// Why an index could not be built over the given points.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum IndexError {
    /// The points and the tie keys differ in number.
    #[error("{points} points but {ties} tie keys: every point needs exactly one")]
    TieLengthMismatch {
        /// Points given.
        points: usize,
        /// Tie keys given.
        ties: usize,
    },
    /// More points than u32 indices can name.
    #[error(
        "{points} points: a kNN index holds at most u32::MAX points (Neighbour::index is u32)"
    )]
    TooManyPoints {
        /// Points given.
        points: usize,
    },
    /// The grid cell size is zero, negative or not finite.
    #[error("grid cell size {cell} is not a positive finite number")]
    BadCellSize {
        /// The size given.
        cell: f64,
    },
    /// kiddo could not build the kd-tree.
    #[error("kd-tree construction failed: {0}")]
    KdTree(#[from] kiddo::kd_tree::ConstructionError),
}

/// Checks what every backend requires of its input.
pub(crate) fn check_input(points: &[DVec3], tie: &[u64]) -> Result<(), IndexError> {
    if points.len() != tie.len() {
        return Err(IndexError::TieLengthMismatch {
            points: points.len(),
            ties: tie.len(),
        });
    }
    if points.len() > u32::MAX as usize {
        return Err(IndexError::TooManyPoints {
            points: points.len(),
        });
    }
    Ok(())
}

/// Builds the chosen kNN structure over `points`, with `tie[i]` the global id
/// of `points[i]`. Both backends give identical answers; they differ in speed.
///
/// Returns an error instead of the bare box because the input can be
/// unusable (tie keys missing, more points than a `u32` index can name).
pub fn build_index<'a>(
    backend: KnnBackend,
    points: &'a [DVec3],
    tie: &'a [u64],
) -> Result<Box<dyn KnnIndex + 'a>, IndexError> {
    Ok(match backend {
        KnnBackend::Grid => Box::new(GridIndex::new(points, tie)?),
        KnnBackend::KdTree => Box::new(KdIndex::new(points, tie)?),
    })
}
