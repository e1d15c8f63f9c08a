//! Per-point inputs of the growth for one tile's loaded points: the
//! neighbour lists (paper 2 section 2.4: exact kNN, or paper 3's
//! topological neighbours), the PCA normal through the neighbourhood's
//! centroid (section 2.5), the local spacing and the thinning (`thin.rs`),
//! all computed in one parallel pass while each list's distances are at
//! hand.
//!
//! Deviation: section 2.4 finds neighbours in a grid of cells
//! `cbrt(volume / n)` searched over 27 cells, which is not exact (the
//! k-th neighbour can lie beyond; PITFALLS.md). The exact kNN of
//! `crate::spatial` gives the same lists in every tile.

use super::cloud::Neighbourhoods;
use super::params::ProjectionParams;
use super::thin::{local_spacing, thinned};
use crate::normals::hood::{HoodIndex, Hoods};
use crate::normals::pca::fit_plane;
use crate::pipeline::KernelError;
use crate::spatial::Neighbour;
use crate::tiling::TilePoints;
use glam::DVec3;

/// What one point contributes beside its list.
#[derive(Clone, Copy, Debug)]
pub struct PointInfo {
    pub normal: DVec3,
    pub spacing: f64,
    pub thinned: bool,
    /// Its neighbour list is certainly complete within the loaded region.
    pub complete: bool,
    /// How far its list may reach beyond the loaded region (0 when it is
    /// exact, so that its plane, spacing and thinning are the whole
    /// cloud's; infinite when fewer than k points were loaded).
    pub short_by: f64,
}

/// The lists of the core points, then those of the margin points.
pub struct TileHoods {
    core: Hoods,
    margin: Hoods,
    n_core: u32,
}

impl Neighbourhoods for TileHoods {
    fn get(&self, i: u32) -> &[u32] {
        if i < self.n_core {
            self.core.get(i as usize)
        } else {
            self.margin.get((i - self.n_core) as usize)
        }
    }
}

/// The loaded points' neighbour lists and point data. Fails with `MarginTooSmall` when a core point's list may reach
/// beyond the loaded region.
pub(crate) fn local_data(
    tile: &TilePoints,
    params: &ProjectionParams,
) -> Result<(TileHoods, Vec<PointInfo>), KernelError> {
    let index = HoodIndex::build(tile, &params.hood())?;
    let visit = |i: usize, nbrs: &[Neighbour]| point_info(tile, params, i, nbrs);
    let n_core = tile.n_core;
    let (core, mut info) = index.hoods(tile, n_core, |i| i, visit)?;
    KernelError::unless_short(core.short_by, tile.margin)?;
    let margin_count = tile.points.len() - n_core;
    let (margin, margin_info) = index.hoods(tile, margin_count, |i| n_core + i, visit)?;
    info.extend(margin_info);
    let n_core = u32::try_from(n_core).map_err(KernelError::failed)?;
    Ok((
        TileHoods {
            core,
            margin,
            n_core,
        },
        info,
    ))
}

/// The lists of some of a tile's points: those in the view of a job the
/// tile runs. The margin is sized for the worst lattice alignment; at 64
/// tiles most of it lies in no such view, and its lists cost a third of
/// the kNN time.
pub struct WantedHoods {
    lists: Hoods,
    /// Where each loaded point's list is in `lists` (`NO_LIST`: never read).
    slot: Vec<u32>,
}

const NO_LIST: u32 = u32::MAX;

impl Neighbourhoods for WantedHoods {
    fn get(&self, i: u32) -> &[u32] {
        match self.slot[i as usize] {
            NO_LIST => &[],
            s => self.lists.get(s as usize),
        }
    }
}

/// The lists and data of the points `wanted` (increasing indices); fails
/// with `MarginTooSmall` when one of their lists may reach beyond the
/// loaded region. The other points get no list and a `PointInfo` that is
/// never complete.
pub(crate) fn wanted_data(
    tile: &TilePoints,
    params: &ProjectionParams,
    wanted: &[u32],
) -> Result<(WantedHoods, Vec<PointInfo>), KernelError> {
    let index = HoodIndex::build(tile, &params.hood())?;
    let visit = |i: usize, nbrs: &[Neighbour]| point_info(tile, params, i, nbrs);
    let (lists, got) = index.hoods(tile, wanted.len(), |j| wanted[j] as usize, visit)?;
    // The search's own reach, and the list's (infinite when fewer than k
    // points were loaded).
    let short = got
        .iter()
        .map(|p| p.short_by)
        .fold(lists.short_by, f64::max);
    KernelError::unless_short(short, tile.margin)?;
    let unread = PointInfo {
        normal: DVec3::ZERO,
        spacing: 0.0,
        thinned: false,
        complete: false,
        short_by: f64::INFINITY,
    };
    let mut info = vec![unread; tile.points.len()];
    let mut slot = vec![NO_LIST; tile.points.len()];
    for (j, (&i, p)) in wanted.iter().zip(got).enumerate() {
        info[i as usize] = p;
        slot[i as usize] = j as u32;
    }
    Ok((WantedHoods { lists, slot }, info))
}

fn point_info(
    tile: &TilePoints,
    params: &ProjectionParams,
    i: usize,
    nbrs: &[Neighbour],
) -> PointInfo {
    let normal = fit_plane(&tile.points, i, nbrs).map_or(DVec3::ZERO, |f| f.normal);
    let spacing = local_spacing(nbrs, params.k).unwrap_or(0.0);
    let reach = nbrs.last().map_or(f64::INFINITY, |n| n.dist2.sqrt());
    let room = tile.room(tile.points[i]);
    // As the list search reports it: fewer than k loaded is complete only
    // when nothing lies beyond.
    let bound = if nbrs.len() >= params.k {
        reach
    } else {
        f64::INFINITY
    };
    PointInfo {
        short_by: if bound <= room { 0.0 } else { bound - room },
        normal,
        spacing,
        thinned: spacing > 0.0 && thinned(tile.ids[i], nbrs, &tile.ids, spacing, params.thin),
        complete: nbrs.len() >= params.k && reach <= tile.room(tile.points[i]),
    }
}
