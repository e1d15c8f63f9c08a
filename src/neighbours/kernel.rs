//! The neighbourhood tile kernel: for every core point of a tile, its
//! topological neighbours (paper 3 steps 1-5, through
//! [`crate::spatial::topological`]) or its plain k nearest neighbours, over
//! the tile's loaded points.
//!
//! A neighbourhood computed from a subset of the points equals the one from
//! all points when every point it could have depended on is loaded: for kNN
//! the ball of the k-th distance, for the mean reverse shift the ball of
//! radius `reach` (largest shift plus that query's k-th distance, see
//! `TopoResult::reach`). The kernel checks that ball against
//! [`TilePoints::room`] for every core point, as the normals kernel does, and
//! otherwise asks for the margin that would make it fit.

use super::stats::HoodStats;
use super::{NeighbourParams, Neighbourhood};
use crate::pipeline::{KernelError, TileKernel};
use crate::spatial::rtree::RTreeIndex;
use crate::spatial::topological::{topological_neighbours, TopoParams, TopoScratch};
use crate::spatial::{build_index, KnnBackend, Neighbour};
use crate::tiling::TilePoints;
use rayon::prelude::*;

/// One tile's neighbourhoods, core points sorted by input-order id.
#[derive(Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct NeighboursTile {
    /// Input-order ids of the core points, ascending.
    pub ids: Vec<u64>,
    /// `neighbours[offsets[i]..offsets[i + 1]]` is the list of `ids[i]`.
    pub offsets: Vec<u64>,
    /// Input-order ids, each list sorted by (distance, id).
    pub neighbours: Vec<u64>,
    /// Size and iteration histograms of the core points.
    pub stats: HoodStats,
}

impl NeighboursTile {
    /// Whether a saved result fits tile `t` of a store of `points` points:
    /// one ascending id per core point, offsets that partition the lists,
    /// every id in the store.
    pub(crate) fn fits(&self, t: &crate::store::TileEntry, points: u64) -> bool {
        let o = &self.offsets;
        let partitions = o.len() == self.ids.len() + 1
            && o.first() == Some(&0)
            && o.last() == Some(&(self.neighbours.len() as u64))
            && o.windows(2).all(|w| w[0] <= w[1]);
        let longest = o.windows(2).map(|w| w[1] - w[0]).max().unwrap_or(0);
        self.ids.len() as u64 == t.count
            && self.ids.windows(2).all(|w| w[0] < w[1])
            && self.ids.iter().chain(&self.neighbours).all(|&i| i < points)
            && partitions
            && self.stats.fits(t.count, longest as usize)
    }
}

/// The tile kernel of the neighbours pass: each core point's list in input-order ids.
pub struct NeighboursKernel {
    /// Which neighbourhood to compute.
    pub params: NeighbourParams,
    /// Margin the first load of each tile gets, in the store's coordinate units.
    pub initial_margin: f64,
}

/// One core point's neighbourhood in tile-local indices.
struct Hood {
    local: Vec<u32>,
    /// Iterations and cap flag (topological only).
    iterations: Option<(u32, bool)>,
    /// How much wider the margin must be for this neighbourhood to be
    /// certainly complete (0 when it is).
    short_by: f64,
}

impl TileKernel for NeighboursKernel {
    type Output = NeighboursTile;

    fn name(&self) -> &'static str {
        crate::store::StageId::NEIGHBOURS.name()
    }

    fn codec(&self) -> Option<crate::pipeline::Codec<Self::Output>> {
        Some(crate::pipeline::Codec::serde(NeighboursTile::fits))
    }

    fn margin(&self) -> f64 {
        self.initial_margin
    }

    fn run(&self, tile: &TilePoints) -> Result<NeighboursTile, KernelError> {
        let hoods = match self.params.neighbourhood {
            Neighbourhood::Topological(p) => topological(tile, &p)?,
            Neighbourhood::Knn { k } => nearest(tile, k, self.params.backend)?,
        };
        let short = hoods.iter().map(|h| h.short_by).fold(0.0, f64::max);
        KernelError::unless_short(short, tile.margin)?;
        Ok(assemble(tile, &hoods))
    }
}

/// Paper 3 for every core point, over an R*-tree of the loaded points.
fn topological(tile: &TilePoints, params: &TopoParams) -> Result<Vec<Hood>, KernelError> {
    let index = RTreeIndex::new(&tile.points, &tile.ids).map_err(KernelError::failed)?;
    let n = u32::try_from(tile.n_core).map_err(KernelError::failed)?;
    (0..n)
        .into_par_iter()
        .map_init(TopoScratch::new, |scratch, i| {
            let r = topological_neighbours(&index, &tile.points, &tile.ids, i, params, scratch)
                .map_err(KernelError::failed)?;
            Ok(Hood {
                local: r.neighbours.iter().map(|nb| nb.index).collect(),
                iterations: Some((r.iterations, r.hit_cap)),
                short_by: tile.shortfall(tile.points[i as usize], r.reach),
            })
        })
        .collect()
}

/// Exact kNN of every core point (the point itself excluded).
fn nearest(tile: &TilePoints, k: usize, backend: KnnBackend) -> Result<Vec<Hood>, KernelError> {
    let index = build_index(backend, &tile.points, &tile.ids).map_err(KernelError::failed)?;
    let index = index.as_ref();
    let n = u32::try_from(tile.n_core).map_err(KernelError::failed)?;
    Ok((0..n)
        .into_par_iter()
        .map_init(Vec::<Neighbour>::new, |found, i| {
            let p = tile.points[i as usize];
            index.knn(p, k, Some(i), found);
            let reach = match found.last() {
                Some(last) if found.len() >= k => last.dist2.sqrt(),
                // Fewer than k loaded: complete only if nothing lies beyond.
                _ if k > 0 => f64::INFINITY,
                _ => 0.0,
            };
            Hood {
                local: found.iter().map(|nb| nb.index).collect(),
                iterations: None,
                short_by: tile.shortfall(p, reach),
            }
        })
        .collect())
}

/// Core lists in input-order ids, points sorted by id.
fn assemble(tile: &TilePoints, hoods: &[Hood]) -> NeighboursTile {
    let mut order: Vec<usize> = (0..hoods.len()).collect();
    order.sort_unstable_by_key(|&i| tile.ids[i]);
    let total: usize = hoods.iter().map(|h| h.local.len()).sum();
    let mut out = NeighboursTile {
        ids: Vec::with_capacity(hoods.len()),
        offsets: Vec::with_capacity(hoods.len() + 1),
        neighbours: Vec::with_capacity(total),
        stats: HoodStats::default(),
    };
    out.offsets.push(0);
    for i in order {
        let h = &hoods[i];
        out.ids.push(tile.ids[i]);
        out.neighbours
            .extend(h.local.iter().map(|&j| tile.ids[j as usize]));
        out.offsets.push(out.neighbours.len() as u64);
        out.stats.add(h.local.len(), h.iterations);
    }
    out
}
