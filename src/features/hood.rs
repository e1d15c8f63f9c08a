//! The curvature fit's neighbourhood over one tile (paper 5 section 2): every
//! point within `r` (the paper's default for uniform sampling), the `k`
//! nearest (its choice for curvature-adaptive sampling) or paper 3's
//! topological neighbours. Each answers in an order no tiling changes (the
//! k-queries in (dist2, id) order, the radius query in the grid's canonical
//! order) with the point itself excluded, and says how far its answer
//! reaches, so the kernel can check the answer lies inside the loaded
//! region.

use super::CurvatureHood;
use crate::pipeline::{KernelError, TileFault};
use crate::spatial::rtree::RTreeIndex;
use crate::spatial::topological::{topological_neighbours, TopoParams, TopoScratch};
use crate::spatial::BallGrid;
use crate::spatial::{build_index, KnnBackend, KnnIndex, Neighbour};
use crate::tiling::TilePoints;

/// A built neighbourhood index over a tile's loaded points.
pub(crate) enum HoodIndex<'a> {
    Radius(BallGrid<'a>, f64),
    Knn(Box<dyn KnnIndex + 'a>, usize),
    Topological(RTreeIndex<'a>, TopoParams),
}

/// Per-worker buffers.
#[derive(Default)]
pub(crate) struct HoodScratch {
    pub nbrs: Vec<Neighbour>,
    topo: TopoScratch,
}

impl<'a> HoodIndex<'a> {
    /// The index for `hood` (its radius absolute) over `tile`'s points.
    pub(crate) fn build(tile: &'a TilePoints, hood: CurvatureHood) -> Result<Self, KernelError> {
        let (points, ids) = (&tile.points[..], &tile.ids[..]);
        Ok(match hood {
            CurvatureHood::Radius(r) => HoodIndex::Radius(
                BallGrid::new(points, ids, r).ok_or(KernelError::Failed(
                    TileFault::CurvatureRadius { radius: r },
                ))?,
                r,
            ),
            CurvatureHood::Knn(k) => HoodIndex::Knn(
                build_index(KnnBackend::Grid, points, ids).map_err(KernelError::failed)?,
                k,
            ),
            CurvatureHood::Topological { k, max_iterations } => HoodIndex::Topological(
                RTreeIndex::new(points, ids).map_err(KernelError::failed)?,
                TopoParams { k, max_iterations },
            ),
        })
    }

    /// The grid over the tile's points, for a radius neighbourhood (other
    /// stages query it at their own radii).
    pub(crate) fn radius_grid(&self) -> Option<&BallGrid<'a>> {
        match self {
            HoodIndex::Radius(grid, _) => Some(grid),
            _ => None,
        }
    }

    /// The neighbours of loaded point `i` into `s.nbrs`; returns their
    /// reach (infinite when a k-query found fewer than k points).
    pub(crate) fn query(
        &self,
        tile: &TilePoints,
        i: usize,
        s: &mut HoodScratch,
    ) -> Result<f64, KernelError> {
        let p = tile.points[i];
        Ok(match self {
            HoodIndex::Radius(grid, r) => {
                grid.within(p, *r, Some(i as u32), &mut s.nbrs);
                *r
            }
            HoodIndex::Knn(index, k) => {
                index.knn(p, *k, Some(i as u32), &mut s.nbrs);
                match s.nbrs.last() {
                    Some(n) if s.nbrs.len() >= *k => n.dist2.sqrt(),
                    _ => f64::INFINITY,
                }
            }
            HoodIndex::Topological(index, params) => {
                let q = u32::try_from(i).map_err(KernelError::failed)?;
                let r =
                    topological_neighbours(index, &tile.points, &tile.ids, q, params, &mut s.topo)
                        .map_err(KernelError::failed)?;
                s.nbrs = r.neighbours;
                r.reach
            }
        })
    }

    /// The points around an arbitrary position `at` (no point excluded)
    /// into `s.nbrs`, and their reach: within `r`, or the k nearest (for
    /// the topological kind too: the reverse shift is defined at data
    /// points only).
    pub(crate) fn around(&self, at: glam::DVec3, s: &mut HoodScratch) -> f64 {
        let (index, k): (&dyn KnnIndex, usize) = match self {
            HoodIndex::Radius(grid, r) => {
                grid.within(at, *r, None, &mut s.nbrs);
                return *r;
            }
            HoodIndex::Knn(index, k) => (index.as_ref(), *k),
            HoodIndex::Topological(index, params) => (index, params.k),
        };
        index.knn(at, k, None, &mut s.nbrs);
        match s.nbrs.last() {
            Some(n) if s.nbrs.len() >= k => n.dist2.sqrt(),
            _ => f64::INFINITY,
        }
    }
}
