//! The writer side of the local-projection kernel: vertices stream out tile
//! by tile (every core point, in store order, so a vertex's index is its
//! store index), fixed triangles go to a spool with their global piece,
//! frames go to the seam pass (`seam.rs`). At the end the seam is grown,
//! the pieces settled (each root turned to a positive signed volume, see
//! `orient.rs`) and the spool replayed into the mesh writer with every
//! triangle wound in its root's settled frame.
//!
//! Memory: the frames and one spool buffer; triangles wait on disk
//! (16 bytes each).

use super::kernel::ProjectionTile;
use super::orient::flipped;
use super::params::ProjectionParams;
use super::seam::{SeamBuilder, SeamResult};
use crate::io::IoError;
use crate::mesh::write::scratch_beside;
use crate::mesh::{MeshError, MeshWriter};
use crate::store::{PointStore, StoreError, TileEntry};
use std::fs::File;
use std::io::{BufReader, BufWriter, Read, Seek, SeekFrom, Write};
use std::path::PathBuf;

/// Counts of what was written.
#[derive(Clone, Copy, Debug, Default)]
pub struct StitchReport {
    pub vertices: u64,
    pub triangles: u64,
    /// Triangles the seam pass added.
    pub seam_triangles: u64,
    pub seam_processed: u64,
    pub pieces: u64,
}

#[derive(Debug, thiserror::Error)]
pub enum StitchError {
    #[error(transparent)]
    Mesh(#[from] MeshError),
    #[error(transparent)]
    Store(#[from] StoreError),
    #[error(transparent)]
    Io(#[from] IoError),
    #[error("seam pass: {0}")]
    Index(#[from] crate::spatial::IndexError),
    #[error("tile {tile}: its vertices would start at {got}, not at its store index {expected}")]
    VertexOrder {
        tile: usize,
        got: u32,
        expected: u64,
    },
}

pub struct Stitcher {
    writer: MeshWriter,
    spool_path: PathBuf,
    spool: BufWriter<File>,
    spooled: u64,
    seam: SeamBuilder,
    piece_volume: Vec<f64>,
    points: Vec<glam::DVec3>,
}

const RECORD: usize = 16;

impl Stitcher {
    pub fn new(writer: MeshWriter) -> Result<Self, StitchError> {
        let spool_path = writer.path().to_path_buf();
        let file = scratch_beside(&spool_path).map_err(|e| IoError::os(&spool_path, e))?;
        Ok(Stitcher {
            writer,
            spool_path,
            spool: BufWriter::with_capacity(1 << 20, file),
            spooled: 0,
            seam: SeamBuilder::default(),
            piece_volume: Vec::new(),
            points: Vec::new(),
        })
    }

    fn io(&self, e: std::io::Error) -> StitchError {
        StitchError::Io(IoError::os(&self.spool_path, e))
    }

    /// One tile's vertices, fixed triangles and frame, in tile order.
    pub fn add_tile(
        &mut self,
        store: &PointStore,
        index: usize,
        entry: &TileEntry,
        tile: &ProjectionTile,
    ) -> Result<(), StitchError> {
        store.read_points(entry.start, entry.count, &mut self.points)?;
        let origin = store.origin();
        self.points.iter_mut().for_each(|p| *p += origin);
        let first = self.writer.add_vertices(&self.points)?;
        if u64::from(first) != entry.start {
            return Err(StitchError::VertexOrder {
                tile: index,
                got: first,
                expected: entry.start,
            });
        }
        let offset = self.piece_volume.len() as u32;
        for (t, &piece) in tile.fixed.iter().zip(&tile.fixed_piece) {
            let mut record = [0u8; RECORD];
            for (k, v) in t.iter().chain([offset + piece].iter()).enumerate() {
                record[4 * k..4 * k + 4].copy_from_slice(&v.to_le_bytes());
            }
            self.spool.write_all(&record).map_err(|e| self.io(e))?;
        }
        self.spooled += tile.fixed.len() as u64;
        self.seam.add(tile, offset);
        self.piece_volume.extend_from_slice(&tile.piece_volume);
        Ok(())
    }

    /// Grows the seam, settles the pieces and writes every triangle.
    pub fn finish(mut self, params: &ProjectionParams) -> Result<StitchReport, StitchError> {
        let pieces = self.piece_volume.len() as u32;
        let seam = std::mem::take(&mut self.seam).grow(params, pieces)?;
        let flip_root = self.root_flips(&seam);
        let settled = |root: u32, flip: bool| flip ^ flip_root[root as usize];
        self.spool.flush().map_err(|e| self.io(e))?;
        let mut file = self.spool.get_ref().try_clone().map_err(|e| self.io(e))?;
        file.seek(SeekFrom::Start(0)).map_err(|e| self.io(e))?;
        let mut reader = BufReader::with_capacity(1 << 20, file);
        let mut batch = Vec::with_capacity(1 << 16);
        let mut record = [0u8; RECORD];
        for _ in 0..self.spooled {
            reader.read_exact(&mut record).map_err(|e| self.io(e))?;
            let word = |k: usize| {
                u32::from_le_bytes([
                    record[4 * k],
                    record[4 * k + 1],
                    record[4 * k + 2],
                    record[4 * k + 3],
                ])
            };
            let t = [word(0), word(1), word(2)];
            let (root, flip) = seam.piece_roots[word(3) as usize];
            batch.push(if settled(root, flip) { flipped(t) } else { t });
            if batch.len() == batch.capacity() {
                self.writer.add_triangles(&batch)?;
                batch.clear();
            }
        }
        for (&t, &(root, flip)) in seam.triangles.iter().zip(&seam.orientation) {
            batch.push(if settled(root, flip) { flipped(t) } else { t });
        }
        self.writer.add_triangles(&batch)?;
        let (vertices, triangles) = self.writer.finish()?;
        Ok(StitchReport {
            vertices,
            triangles,
            seam_triangles: seam.triangles.len() as u64,
            seam_processed: seam.processed,
            pieces: u64::from(pieces),
        })
    }

    /// Whether each root of the seam's pieces must be flipped: when the
    /// signed volume of everything it holds is negative.
    fn root_flips(&self, seam: &SeamResult) -> Vec<bool> {
        let mut volume = vec![0.0f64; seam.elements];
        for (p, &(root, flip)) in seam.piece_roots.iter().enumerate() {
            let v = self.piece_volume[p];
            volume[root as usize] += if flip { -v } else { v };
        }
        for (&(root, _), &v) in seam.orientation.iter().zip(&seam.volumes) {
            volume[root as usize] += v;
        }
        volume.into_iter().map(|v| v < 0.0).collect()
    }
}
