//! The normals kernel's neighbourhood provider: for a loaded point, the
//! neighbours its tangent plane and its Riemannian-graph edges use, and how
//! far the loaded region falls short of holding everything they depend on.
//!
//! Two kinds ([`super::NormalHood`]): the exact k nearest (paper 1 section 2.2)
//! over the chosen kNN backend, or paper 3's topological neighbours (mean
//! reverse shift, [`crate::spatial::topological`]) over its R*-tree. Both
//! exclude the point itself (`fit_plane` adds it) and sort by (dist2, global
//! id), so the lists, and everything computed from them, do not depend on
//! the tiling. The dependence radius is the k-th distance for kNN and
//! [`TopoResult::reach`](crate::spatial::topological::TopoResult::reach) for
//! the reverse shift; either is infinite when a query found fewer than k
//! points (then only a tile holding everything is complete).

use super::NormalParams;
use crate::pipeline::KernelError;
use crate::spatial::rtree::RTreeIndex;
use crate::spatial::topological::{topological_neighbours, TopoParams, TopoScratch};
use crate::spatial::{build_index, KnnIndex, Neighbour};
use crate::tiling::TilePoints;
use rayon::prelude::*;

/// Neighbourhood of one point: its neighbours and the room check.
pub(super) struct Hood {
    pub nbrs: Vec<Neighbour>,
    /// How much wider the margin must be for this neighbourhood to be
    /// certainly complete (0 when it is).
    pub short_by: f64,
}

/// An index over one tile's loaded points, answering [`Hood`]s.
pub(super) enum HoodIndex<'a> {
    Knn {
        index: Box<dyn KnnIndex + 'a>,
        k: usize,
    },
    Topological {
        index: RTreeIndex<'a>,
        params: TopoParams,
    },
}

fn failed(e: impl std::fmt::Display) -> KernelError {
    KernelError::Failed(e.to_string())
}

impl<'a> HoodIndex<'a> {
    /// Builds the index `params.neighbourhood` needs over the tile's points.
    pub fn build(tile: &'a TilePoints, params: &NormalParams) -> Result<Self, KernelError> {
        let (points, ids) = (&tile.points[..], &tile.ids[..]);
        Ok(match params.neighbourhood.topo_params(params.k) {
            None => HoodIndex::Knn {
                index: build_index(params.backend, points, ids).map_err(failed)?,
                k: params.k,
            },
            Some(params) => HoodIndex::Topological {
                index: RTreeIndex::new(points, ids).map_err(failed)?,
                params,
            },
        })
    }

    /// The neighbourhood of loaded point `i`.
    pub fn hood(
        &self,
        tile: &TilePoints,
        i: usize,
        scratch: &mut TopoScratch,
    ) -> Result<Hood, KernelError> {
        let (nbrs, reach) = match self {
            HoodIndex::Knn { index, k } => knn(index.as_ref(), tile, i, *k),
            HoodIndex::Topological { index, params } => {
                let i = u32::try_from(i).map_err(failed)?;
                let r = topological_neighbours(index, &tile.points, &tile.ids, i, params, scratch)
                    .map_err(failed)?;
                (r.neighbours, r.reach)
            }
        };
        let room = tile.room(tile.points[i]);
        let short_by = if reach <= room { 0.0 } else { reach - room };
        Ok(Hood { nbrs, short_by })
    }

    /// The neighbourhoods of `points`, in their order, with one scratch per
    /// worker. Each depends only on its point, so the thread count does not
    /// matter.
    pub fn hoods<I>(&self, tile: &TilePoints, points: I) -> Result<Vec<Hood>, KernelError>
    where
        I: IndexedParallelIterator<Item = usize>,
    {
        points
            .map_init(TopoScratch::new, |scratch, i| self.hood(tile, i, scratch))
            .collect()
    }
}

/// The k nearest of point `i` (itself excluded) and their k-th distance.
fn knn(index: &dyn KnnIndex, tile: &TilePoints, i: usize, k: usize) -> (Vec<Neighbour>, f64) {
    let mut nbrs = Vec::with_capacity(k + 4);
    index.knn(tile.points[i], k, Some(i as u32), &mut nbrs);
    let reach = match nbrs.last() {
        Some(n) if nbrs.len() >= k => n.dist2.sqrt(),
        // Fewer than k loaded: complete only if nothing lies beyond.
        _ => f64::INFINITY,
    };
    (nbrs, reach)
}
