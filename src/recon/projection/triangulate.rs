//! Paper 2 over one tile's loaded points, start to end: neighbourhoods and
//! planes (`local.rs`), then the growth (`grow.rs`) from the core points in
//! input-id order. A pure function of the points.

use super::cloud::Cloud;
use super::grow::Grower;
use super::local::{local_data, PointInfo, TileHoods};
use super::orient::settle;
use super::params::ProjectionParams;
use super::probe::Probe;
use super::surface::{State, Surface};
use crate::pipeline::KernelError;
use crate::tiling::TilePoints;
use glam::DVec3;

/// The grown surface of a tile, over its loaded points.
pub struct TileSurface {
    pub surface: Surface,
    pub info: Vec<PointInfo>,
    pub hoods: TileHoods,
    pub processed: u64,
}

/// Grows the local-projection surface over the points of one tile, margins included.
pub fn triangulate_tile(
    tile: &TilePoints,
    params: &ProjectionParams,
) -> Result<TileSurface, KernelError> {
    let (hoods, info) = local_data(tile, params)?;
    let normals: Vec<DVec3> = info.iter().map(|p| p.normal).collect();
    let spacing: Vec<f64> = info.iter().map(|p| p.spacing).collect();
    let centre: Vec<bool> = info.iter().map(|p| p.complete).collect();
    let joinable = vec![true; tile.points.len()];
    let probe = Probe::new(&tile.points, &tile.ids, &spacing);
    let cloud = Cloud {
        points: &tile.points,
        normals: &normals,
        spacing: &spacing,
        hoods: &hoods,
        centre: &centre,
        joinable: &joinable,
        probe: &probe,
        slack: 0.0,
    };
    let mut surface = Surface::new(tile.points.len());
    for (state, p) in surface.state.iter_mut().zip(&info) {
        if p.thinned || p.spacing == 0.0 {
            *state = State::Unused;
        }
    }
    let mut seeds: Vec<u32> = (0..tile.n_core as u32).collect();
    seeds.sort_unstable_by_key(|&i| tile.ids[i as usize]);
    let mut grower = Grower::new(params, tile.points.len());
    grower.grow(&cloud, &mut surface, &seeds);
    let processed = grower.processed;
    Ok(TileSurface {
        surface,
        info,
        hoods,
        processed,
    })
}

/// Paper 2 over points in memory (one tile holding everything): the
/// triangles, indexing `points`, wound consistently and outward (see
/// `orient.rs`), and how many points were left unused.
pub fn triangulate_points(
    points: &[DVec3],
    params: &ProjectionParams,
) -> Result<(Vec<[u32; 3]>, TileSurface), KernelError> {
    let tile = TilePoints::whole(points.to_vec());
    let mut grown = triangulate_tile(&tile, params)?;
    let low = points.iter().fold(DVec3::INFINITY, |m, p| m.min(*p));
    let triangles = settle(&mut grown.surface, points, low);
    Ok((triangles, grown))
}
