//! The implicit kernel's seam policy: triangles arrive tile by tile with
//! vertices keyed by global lattice edge; each key gets one output index.
//! An edge all of whose four cubes belong to the arriving tile is private
//! and forgotten after the tile; an edge on the tile's boundary may be met
//! again by a neighbour, so its index stays in a map until the last tile
//! owning one of its cubes has been stitched ([`super::owners`]): the map
//! holds the front between stitched and unstitched tiles, not every seam. Output indices are given in first-appearance
//! order, so the mesh is the same for a given tiling and thread count.

use super::cubes::owns;
use super::lattice::{edge_from_key, Lattice};
use super::owners::TileOwners;
use super::polygonize::CubeVertex;
use crate::geom::Aabb;
use crate::mesh::{MeshAudit, MeshError, PieceFilter, PieceReport};
use glam::DVec3;
use std::collections::HashMap;

/// What the stitcher wrote, and what it did to small pieces.
#[derive(Clone, Copy, Debug, Default)]
pub struct StitchReport {
    pub vertices: u64,
    pub triangles: u64,
    pub pieces: PieceReport,
    /// The writer's audit of the mesh written.
    pub audit: MeshAudit,
    /// Seam state left at the end: 0 unless a vertex's owners were not
    /// found (tests check it).
    pub seam_left: u64,
}

/// A seam vertex's output index and the last tile that may name it.
#[derive(Clone, Copy)]
struct SeamVertex {
    index: u32,
    last: u32,
}

pub struct Stitcher {
    writer: PieceFilter,
    /// Offset from lattice (store-relative) coordinates to output ones.
    origin: DVec3,
    shared: HashMap<u64, SeamVertex>,
    private: HashMap<u64, u32>,
    owners: TileOwners,
    pub vertices: u64,
    pub triangles: u64,
}

impl Stitcher {
    /// `cores`: every tile's core box, in the order tiles will arrive.
    pub fn new(writer: PieceFilter, origin: DVec3, cores: Vec<Aabb>) -> Self {
        Stitcher {
            writer,
            origin,
            shared: HashMap::new(),
            private: HashMap::new(),
            owners: TileOwners::new(cores),
            vertices: 0,
            triangles: 0,
        }
    }

    /// Adds tile `tile`'s triangles (tiles arrive in order); `core` is its
    /// core box.
    pub fn add_tile(
        &mut self,
        lattice: &Lattice,
        (tile, core): (usize, &Aabb),
        tris: &[[CubeVertex; 3]],
    ) -> Result<(), MeshError> {
        let around = self.owners.around(tile, lattice.cell);
        self.private.clear();
        let mut new_vertices = Vec::new();
        let mut faces: Vec<[u32; 3]> = Vec::with_capacity(tris.len());
        for t in tris {
            let mut face = [0u32; 3];
            for i in 0..3 {
                let v = &t[i];
                let next = (self.vertices + new_vertices.len() as u64) as u32;
                let mut add = || {
                    new_vertices.push(self.origin + v.pos);
                    next
                };
                if touches_other_tiles(lattice, core, v.key) {
                    let owners = &self.owners;
                    let entry = self.shared.entry(v.key).or_insert_with(|| SeamVertex {
                        index: add(),
                        last: owners.last_owner(lattice, &around, v.key),
                    });
                    face[i] = entry.index;
                } else {
                    face[i] = *self.private.entry(v.key).or_insert_with(add);
                }
            }
            faces.push(face);
        }
        self.shared.retain(|_, v| v.last > tile as u32);
        self.writer.add_vertices(&new_vertices)?;
        self.writer.add_triangles(&faces)?;
        self.vertices += new_vertices.len() as u64;
        self.triangles += faces.len() as u64;
        Ok(())
    }

    /// Completes the file.
    pub fn finish(self) -> Result<StitchReport, MeshError> {
        let mut report = StitchReport {
            seam_left: self.shared.len() as u64,
            ..StitchReport::default()
        };
        let (written, pieces) = self.writer.finish()?;
        (report.vertices, report.triangles) = written.counts();
        report.pieces = pieces;
        report.audit = written.audit;
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
