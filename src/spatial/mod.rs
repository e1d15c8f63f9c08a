//! Spatial queries over one tile's points: exact k-nearest neighbours by a
//! uniform grid (paper 1 section 2.1) or a kd-tree (kiddo), and a brute-force
//! oracle for tests.
//!
//! Every backend returns the same answer bit for bit: neighbours sorted by
//! (squared distance, tie key), where the squared distance is always computed
//! as `(points[i] - q).length_squared()` in f64 and the tie key is the point's
//! global id (its original input index). That is what makes tiled runs equal
//! untiled ones.

use glam::DVec3;

pub mod rtree;
pub mod topological;

/// One neighbour: its position in the slice the index was built over.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Neighbour {
    pub dist2: f64,
    pub index: u32,
}

/// Exact k-nearest-neighbour search over a fixed set of points.
pub trait KnnIndex: Sync {
    /// Clears `out`, then fills it with the `k` nearest points to `q`
    /// (fewer if the index holds fewer), skipping the point at `exclude`,
    /// sorted by (dist2, tie key). Exact: never an approximation.
    fn knn(&self, q: DVec3, k: usize, exclude: Option<u32>, out: &mut Vec<Neighbour>);
    fn len(&self) -> usize;
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// Which kNN structure to build.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum KnnBackend {
    /// Uniform grid with a search that widens until the k-th distance lies
    /// inside the searched block.
    Grid,
    /// kiddo's immutable kd-tree, asked for extra neighbours to settle ties.
    #[default]
    KdTree,
}
