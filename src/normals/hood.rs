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
//!
//! Storage: only the neighbours' local indices are kept (`Hoods`), four
//! bytes each in chunks of `CHUNK` points. A `Vec<Neighbour>` per point
//! cost ~280 bytes a point at k = 12 (16-byte entries, spare capacity, the
//! vector itself): a third of the 1M-point run's peak, and its page faults
//! were ~8 % of the CPU time. Whatever needs the distances (the plane fit,
//! the sampling statistics) is computed from the full list while it is at
//! hand, by the `visit` callback of `HoodIndex::hoods`.

use super::NormalParams;
use crate::pipeline::KernelError;
use crate::spatial::rtree::RTreeIndex;
use crate::spatial::topological::{topological_neighbours, TopoParams, TopoScratch};
use crate::spatial::{build_index, KnnIndex, Neighbour};
use crate::tiling::TilePoints;
use rayon::prelude::*;

/// Points per storage chunk: one rayon task each, so also the grain of the
/// parallel loop (enough tasks to balance two to a few dozen threads).
const CHUNK: usize = 1024;

/// The neighbour lists (local indices) of a sequence of loaded points.
pub(crate) struct Hoods {
    chunks: Vec<HoodChunk>,
    /// How much wider the margin must be for every list to be certainly
    /// complete (0 when it is).
    pub short_by: f64,
}

/// The lists of up to [`CHUNK`] consecutive points, end to end.
#[derive(Default)]
struct HoodChunk {
    /// `ends[i]` is where point i's list ends in `nbrs`.
    ends: Vec<u32>,
    nbrs: Vec<u32>,
}

impl Hoods {
    /// The neighbours of the `n`-th point of the sequence, nearest first.
    pub fn get(&self, n: usize) -> &[u32] {
        let chunk = &self.chunks[n / CHUNK];
        let i = n % CHUNK;
        let start = if i == 0 { 0 } else { chunk.ends[i - 1] };
        &chunk.nbrs[start as usize..chunk.ends[i] as usize]
    }

    /// Every list, in order.
    pub fn iter(&self) -> impl Iterator<Item = &[u32]> + '_ {
        self.chunks.iter().flat_map(|c| {
            let starts = std::iter::once(0).chain(c.ends.iter().copied());
            starts
                .zip(&c.ends)
                .map(|(s, &e)| &c.nbrs[s as usize..e as usize])
        })
    }
}

/// An index over one tile's loaded points, answering neighbourhoods.
pub(crate) enum HoodIndex<'a> {
    Knn {
        index: Box<dyn KnnIndex + 'a>,
        k: usize,
    },
    Topological {
        index: RTreeIndex<'a>,
        params: TopoParams,
    },
}

/// Per-worker query buffers.
struct Scratch {
    topo: TopoScratch,
    nbrs: Vec<Neighbour>,
}

impl<'a> HoodIndex<'a> {
    /// Builds the index `params.neighbourhood` needs over the tile's points.
    pub fn build(tile: &'a TilePoints, params: &NormalParams) -> Result<Self, KernelError> {
        let (points, ids) = (&tile.points[..], &tile.ids[..]);
        Ok(match params.neighbourhood.topo_params(params.k) {
            None => HoodIndex::Knn {
                index: build_index(params.backend, points, ids).map_err(KernelError::failed)?,
                k: params.k,
            },
            Some(params) => HoodIndex::Topological {
                index: RTreeIndex::new(points, ids).map_err(KernelError::failed)?,
                params,
            },
        })
    }

    /// The usual list length: k for kNN; about 2k for the reverse shift
    /// (paper 3: `|T|` in `[k, 3k]`).
    fn typical_len(&self) -> usize {
        match self {
            HoodIndex::Knn { k, .. } => *k,
            HoodIndex::Topological { params, .. } => 2 * params.k,
        }
    }

    /// The neighbours of loaded point `i` into `scratch.nbrs`, and how much
    /// wider the margin must be for them to be certainly complete.
    fn query(
        &self,
        tile: &TilePoints,
        i: usize,
        scratch: &mut Scratch,
    ) -> Result<f64, KernelError> {
        let reach = match self {
            HoodIndex::Knn { index, k } => knn(index.as_ref(), tile, i, *k, &mut scratch.nbrs),
            HoodIndex::Topological { index, params } => {
                let i = u32::try_from(i).map_err(KernelError::failed)?;
                let r = topological_neighbours(
                    index,
                    &tile.points,
                    &tile.ids,
                    i,
                    params,
                    &mut scratch.topo,
                )
                .map_err(KernelError::failed)?;
                scratch.nbrs = r.neighbours;
                r.reach
            }
        };
        let room = tile.room(tile.points[i]);
        Ok(if reach <= room { 0.0 } else { reach - room })
    }

    /// The neighbourhoods of the points `point_at(0..count)`, in that order,
    /// and `visit(point, its neighbours)` for each, while the distances are
    /// at hand. Each depends only on its point, so the thread count does not
    /// matter.
    pub fn hoods<T, P, V>(
        &self,
        tile: &TilePoints,
        count: usize,
        point_at: P,
        visit: V,
    ) -> Result<(Hoods, Vec<T>), KernelError>
    where
        T: Send,
        P: Fn(usize) -> usize + Sync,
        V: Fn(usize, &[Neighbour]) -> T + Sync,
    {
        let parts: Vec<(HoodChunk, Vec<T>, f64)> = (0..count.div_ceil(CHUNK))
            .into_par_iter()
            .map_init(
                || Scratch {
                    topo: TopoScratch::new(),
                    nbrs: Vec::new(),
                },
                |scratch, c| {
                    let range = c * CHUNK..count.min((c + 1) * CHUNK);
                    self.chunk(tile, range.map(&point_at), &visit, scratch)
                },
            )
            .collect::<Result<_, _>>()?;
        let mut visited = Vec::with_capacity(count);
        let mut hoods = Hoods {
            chunks: Vec::with_capacity(parts.len()),
            short_by: 0.0,
        };
        for (chunk, values, short_by) in parts {
            hoods.chunks.push(chunk);
            visited.extend(values);
            hoods.short_by = hoods.short_by.max(short_by);
        }
        Ok((hoods, visited))
    }

    fn chunk<T, V>(
        &self,
        tile: &TilePoints,
        points: impl ExactSizeIterator<Item = usize>,
        visit: &V,
        scratch: &mut Scratch,
    ) -> Result<(HoodChunk, Vec<T>, f64), KernelError>
    where
        V: Fn(usize, &[Neighbour]) -> T,
    {
        let mut chunk = HoodChunk {
            ends: Vec::with_capacity(points.len()),
            nbrs: Vec::with_capacity(points.len() * self.typical_len()),
        };
        let mut values = Vec::with_capacity(points.len());
        let mut short_by = 0.0f64;
        for i in points {
            short_by = short_by.max(self.query(tile, i, scratch)?);
            values.push(visit(i, &scratch.nbrs));
            chunk.nbrs.extend(scratch.nbrs.iter().map(|n| n.index));
            chunk
                .ends
                .push(u32::try_from(chunk.nbrs.len()).map_err(KernelError::failed)?);
        }
        chunk.nbrs.shrink_to_fit();
        Ok((chunk, values, short_by))
    }
}

/// The k nearest of point `i` (itself excluded) into `nbrs`, and their k-th
/// distance.
fn knn(
    index: &dyn KnnIndex,
    tile: &TilePoints,
    i: usize,
    k: usize,
    nbrs: &mut Vec<Neighbour>,
) -> f64 {
    index.knn(tile.points[i], k, Some(i as u32), nbrs);
    match nbrs.last() {
        Some(n) if nbrs.len() >= k => n.dist2.sqrt(),
        // Fewer than k loaded: complete only if nothing lies beyond.
        _ => f64::INFINITY,
    }
}
