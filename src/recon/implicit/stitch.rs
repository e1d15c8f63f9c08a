//! The implicit kernel's seam policy: triangles arrive tile by tile with
//! vertices keyed by global lattice edge; each key gets one output index.
//! An edge all of whose four cubes belong to the arriving tile is private
//! and forgotten after the tile; an edge on the tile's boundary may be met
//! again by a neighbour, so its index stays in a map (about the seam's
//! size, not the mesh's). Output indices are given in first-appearance
//! order, so the mesh is the same for a given tiling and thread count.
//! Asked to close holes, it also hands every tile's triangles to
//! [`super::holes`], and patches the loops at the end.

use super::holes::{BoundaryEdges, HoleReport, StitchedTriangle};
use super::kernel::owns;
use super::lattice::{edge_from_key, Lattice};
use super::polygonize::CubeVertex;
use crate::geom::Aabb;
use crate::mesh::{MeshError, PieceFilter, PieceReport};
use glam::DVec3;
use std::collections::HashMap;

/// What the stitcher wrote, and what it did to holes and small pieces.
#[derive(Clone, Copy, Debug, Default)]
pub struct StitchReport {
    pub vertices: u64,
    pub triangles: u64,
    pub holes: HoleReport,
    pub pieces: PieceReport,
}

pub struct Stitcher {
    writer: PieceFilter,
    /// Offset from lattice (store-relative) coordinates to output ones.
    origin: DVec3,
    shared: HashMap<u64, u32>,
    private: HashMap<u64, u32>,
    /// Boundary edges, gathered when holes are to be closed.
    holes: Option<BoundaryEdges>,
    pub vertices: u64,
    pub triangles: u64,
}

impl Stitcher {
    pub fn new(writer: PieceFilter, origin: DVec3) -> Self {
        Stitcher {
            writer,
            origin,
            shared: HashMap::new(),
            private: HashMap::new(),
            holes: None,
            vertices: 0,
            triangles: 0,
        }
    }

    /// Closes the mesh's small holes at the end ([`super::holes`]).
    pub fn closing_holes(self) -> Self {
        Stitcher {
            holes: Some(BoundaryEdges::default()),
            ..self
        }
    }

    /// Adds one tile's triangles; `core` is the tile's core box.
    pub fn add_tile(
        &mut self,
        lattice: &Lattice,
        core: &Aabb,
        tris: &[[CubeVertex; 3]],
    ) -> Result<(), MeshError> {
        self.private.clear();
        let mut new_vertices = Vec::new();
        let mut faces = Vec::with_capacity(tris.len());
        let mut stitched = Vec::new();
        for t in tris {
            let mut face = [0u32; 3];
            let mut seam = [false; 3];
            for ((slot, v), on_seam) in face.iter_mut().zip(t).zip(&mut seam) {
                *on_seam = touches_other_tiles(lattice, core, v.key);
                let map = if *on_seam {
                    &mut self.shared
                } else {
                    &mut self.private
                };
                let next = (self.vertices + new_vertices.len() as u64) as u32;
                *slot = *map.entry(v.key).or_insert_with(|| {
                    new_vertices.push(self.origin + v.pos);
                    next
                });
            }
            if self.holes.is_some() {
                stitched.push(StitchedTriangle {
                    vertices: [0, 1, 2].map(|i| (face[i], self.origin + t[i].pos)),
                    on_seam: seam,
                });
            }
            faces.push(face);
        }
        if let Some(holes) = &mut self.holes {
            holes.add_tile(&stitched);
        }
        self.writer.add_vertices(&new_vertices)?;
        self.writer.add_triangles(&faces)?;
        self.vertices += new_vertices.len() as u64;
        self.triangles += faces.len() as u64;
        Ok(())
    }

    /// Closes the holes (if asked) and completes the file.
    pub fn finish(mut self) -> Result<StitchReport, MeshError> {
        let mut report = StitchReport::default();
        if let Some(holes) = self.holes.take() {
            let patches;
            (patches, report.holes) = holes.fill();
            self.writer.add_triangles(&patches)?;
        }
        (report.vertices, report.triangles, report.pieces) = self.writer.finish()?;
        Ok(report)
    }
}

/// Whether a cube sharing lattice edge `key` may belong to another tile:
/// the four cubes around an edge along `axis` have min corners at the edge's
/// corner minus 0 or 1 along each other axis; all are owned iff the two
/// extreme ones are (the core is a box).
fn touches_other_tiles(lattice: &Lattice, core: &Aabb, key: u64) -> bool {
    let Ok((cell, axis)) = edge_from_key(key) else {
        return true;
    };
    let mut low = cell;
    for (a, c) in low.iter_mut().enumerate() {
        if a != axis as usize {
            *c -= 1;
        }
    }
    !(owns(lattice, core, cell) && owns(lattice, core, low))
}
