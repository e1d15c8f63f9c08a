//! The local-projection tile kernel and its seam policy (ARCHITECTURE.md,
//! "Interpolating meshes").
//!
//! Greedy growth depends on where it starts and in which order the front
//! moves, so two tiles grow different meshes near their common face. Each
//! tile therefore grows over its whole loaded region (core and margin) and
//! *fixes* only the triangles whose three vertices are core points at least
//! the band half-width `w` inside its core box; those never overlap another
//! tile's (the shrunk cores are disjoint and apart by `2w`). The band of
//! width `2w` along every tile face is left empty and re-grown afterwards
//! by `seam.rs`, with the fixed triangles as they are (their open vertices
//! FRINGE with their fans). For that pass each tile hands over its *frame*:
//! the core points within `w + frame` of a face, with their planes,
//! spacings and neighbour lists, and its fixed triangles there.
//!
//! Orientation pieces are numbered densely per tile (by first appearance
//! among the fixed triangles), and each fixed triangle is handed over
//! wound in its piece root's frame, with each piece's signed volume.

use super::cloud::Neighbourhoods;
use super::orient::{flipped, volume6};
use super::params::ProjectionParams;
use super::surface::{State, NONE};
use super::triangulate::{triangulate_tile, TileSurface};
use crate::geom::Aabb;
use crate::pipeline::{KernelError, TileKernel};
use crate::tiling::TilePoints;
use glam::DVec3;

/// A core point near the tile's faces, for the seam pass.
#[derive(Clone, Debug)]
pub struct FramePoint {
    /// Store index: the output vertex index.
    pub store: u32,
    pub id: u64,
    /// Store-relative position.
    pub p: DVec3,
    pub normal: DVec3,
    pub spacing: f64,
    pub unused: bool,
    /// Its neighbour list lies inside the frame, so the seam pass may
    /// process it.
    pub centre: bool,
    /// Where its neighbours (store indices) end in `ProjectionTile::hoods`.
    pub hood_end: u32,
}

/// What one tile contributes.
#[derive(Debug, Default)]
pub struct ProjectionTile {
    /// Fixed triangles (store indices), wound in their piece's frame.
    pub fixed: Vec<[u32; 3]>,
    /// Dense tile-local piece of each fixed triangle.
    pub fixed_piece: Vec<u32>,
    /// Six times the signed volume of each piece's fixed triangles, about
    /// the store origin.
    pub piece_volume: Vec<f64>,
    pub frame: Vec<FramePoint>,
    pub hoods: Vec<u32>,
    /// Indices into `fixed` of the triangles with a corner in the frame.
    pub frame_triangles: Vec<u32>,
    /// Corners of those triangles beyond the frame (store index, position).
    pub ghosts: Vec<(u32, DVec3)>,
    /// Points processed by the growth, margin included.
    pub processed: u64,
}

pub struct ProjectionKernel {
    pub params: ProjectionParams,
    /// Half-width of the band re-grown along tile faces.
    pub band: f64,
    /// Width of the frame beyond the band.
    pub frame: f64,
    pub initial_margin: f64,
}

impl TileKernel for ProjectionKernel {
    type Output = ProjectionTile;

    fn name(&self) -> &str {
        "local projection"
    }

    fn margin(&self) -> f64 {
        self.initial_margin
    }

    fn run(&self, tile: &TilePoints) -> Result<ProjectionTile, KernelError> {
        let mut grown = triangulate_tile(tile, &self.params)?;
        let depth: Vec<f64> = (0..tile.n_core)
            .map(|i| face_distance(&tile.core, tile.points[i]))
            .collect();
        let mut out = ProjectionTile {
            processed: grown.processed,
            ..ProjectionTile::default()
        };
        self.fix_triangles(tile, &mut grown, &depth, &mut out)?;
        self.hand_over_frame(tile, &grown, &depth, &mut out)?;
        Ok(out)
    }
}

/// Distance from `p` (in the core) to the nearest face of `core` (faces
/// at infinity do not count).
pub fn face_distance(core: &Aabb, p: DVec3) -> f64 {
    (p - core.min).min(core.max - p).min_element()
}

fn store_u32(tile: &TilePoints, i: u32) -> Result<u32, KernelError> {
    u32::try_from(tile.store_index(i as usize)).map_err(|_| {
        KernelError::Failed("more than 2^32 points: mesh indices are 32-bit".to_string())
    })
}

impl ProjectionKernel {
    /// Keeps the triangles whose corners are all core points at least
    /// `band` inside the core, in their piece root's frame.
    fn fix_triangles(
        &self,
        tile: &TilePoints,
        grown: &mut TileSurface,
        depth: &[f64],
        out: &mut ProjectionTile,
    ) -> Result<(), KernelError> {
        let s = &mut grown.surface;
        let mut dense = vec![NONE; tile.points.len()];
        let inner = |v: u32| depth.get(v as usize).is_some_and(|&d| d >= self.band);
        for tri in 0..s.tris.len() as u32 {
            let t = s.tris[tri as usize];
            if !t.iter().all(|&v| inner(v)) {
                continue;
            }
            let (root, flip) = s.orientation(tri);
            if dense[root as usize] == NONE {
                dense[root as usize] = out.piece_volume.len() as u32;
                out.piece_volume.push(0.0);
            }
            let piece = dense[root as usize];
            let t = if flip { flipped(t) } else { t };
            out.piece_volume[piece as usize] += volume6(&tile.points, t, DVec3::ZERO);
            out.fixed.push([
                store_u32(tile, t[0])?,
                store_u32(tile, t[1])?,
                store_u32(tile, t[2])?,
            ]);
            out.fixed_piece.push(piece);
            let near_face = t
                .iter()
                .any(|&v| depth[v as usize] < self.band + self.frame);
            if near_face {
                out.frame_triangles.push(out.fixed.len() as u32 - 1);
            }
        }
        Ok(())
    }

    /// The frame points with their lists, and the far corners of the fixed
    /// triangles that reach into the frame.
    fn hand_over_frame(
        &self,
        tile: &TilePoints,
        grown: &TileSurface,
        depth: &[f64],
        out: &mut ProjectionTile,
    ) -> Result<(), KernelError> {
        let reach = self.band + self.frame;
        let hoods = &grown.hoods;
        for (i, &d) in depth.iter().enumerate() {
            if d >= reach {
                continue;
            }
            let info = grown.info[i];
            let list = hoods.get(i as u32);
            let far = list.last().map_or(f64::INFINITY, |&j| {
                (tile.points[j as usize] - tile.points[i]).length()
            });
            for &j in list {
                out.hoods.push(store_u32(tile, j)?);
            }
            out.frame.push(FramePoint {
                store: store_u32(tile, i as u32)?,
                id: tile.ids[i],
                p: tile.points[i],
                normal: info.normal,
                spacing: info.spacing,
                unused: grown.surface.state[i] == State::Unused,
                centre: info.complete && d + far < reach,
                hood_end: out.hoods.len() as u32,
            });
        }
        let mut ghost = vec![false; tile.n_core];
        for k in 0..out.frame_triangles.len() {
            let t = out.fixed[out.frame_triangles[k] as usize];
            for v in t {
                let local = (u64::from(v) - tile.store_first) as usize;
                if depth[local] >= reach && !ghost[local] {
                    ghost[local] = true;
                    out.ghosts.push((v, tile.points[local]));
                }
            }
        }
        Ok(())
    }
}
