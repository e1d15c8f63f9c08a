//! The writer side of the local-projection kernel: vertices stream out tile
//! by tile (every core point, in store order, so a vertex's index is its
//! store index), triangles go to a spool with their piece. At the end the
//! pieces are settled: a parity union-find over the pieces (a few per
//! lattice job) joined by the relations the jobs found, each root turned
//! to a positive signed volume (`orient.rs`); then the spool is replayed
//! into the mesh writer with every triangle wound in its root's frame.
//!
//! Memory: the pieces (name, volume, relations: a few dozen bytes per
//! lattice job) and one spool buffer; triangles wait on disk (16 bytes
//! each).

use super::kernel::ProjectionTile;
use super::orient::flipped;
use crate::io::IoError;
use crate::mesh::runs::RunSizes;
use crate::mesh::scratch::scratch_beside;
use crate::mesh::wound::SameWay;
use crate::mesh::{MeshAudit, MeshError, MeshWriter};
use crate::normals::unionfind::ParityUnionFind;
use crate::store::{PointStore, StoreError, TileEntry};
use std::collections::HashMap;
use std::fs::File;
use std::io::{BufReader, BufWriter, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

/// Counts of what was written.
#[derive(Clone, Copy, Debug, Default)]
pub struct StitchReport {
    pub vertices: u64,
    pub triangles: u64,
    pub pieces: u64,
    /// Relations between pieces that contradicted earlier ones (a
    /// non-orientable join no job could see).
    pub contradictions: u64,
    /// Triangles left out so that no edge is run twice the same way (one
    /// per such edge, where contradicting relations met).
    pub left_out: u64,
}

#[derive(Debug, thiserror::Error)]
pub enum StitchError {
    #[error(transparent)]
    Mesh(#[from] MeshError),
    #[error(transparent)]
    Store(#[from] StoreError),
    #[error(transparent)]
    Io(#[from] IoError),
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
    /// Piece name -> dense piece.
    pieces: HashMap<u64, u32>,
    piece_volume: Vec<f64>,
    relations: Vec<(u32, u32, bool)>,
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
            pieces: HashMap::new(),
            piece_volume: Vec::new(),
            relations: Vec::new(),
            points: Vec::new(),
        })
    }

    fn io(&self, e: std::io::Error) -> StitchError {
        StitchError::Io(IoError::os(&self.spool_path, e))
    }

    /// One tile's vertices, triangles and pieces, in tile order.
    pub fn add_tile(
        &mut self,
        store: &PointStore,
        index: usize,
        entry: &TileEntry,
        tile: &ProjectionTile,
    ) -> Result<(), StitchError> {
        // The input's own coordinates, not the store's f32 offsets.
        store.read_exact_in_store_order(entry.start, entry.count, &mut self.points)?;
        let first = self.writer.add_vertices(&self.points)?;
        if u64::from(first) != entry.start {
            return Err(StitchError::VertexOrder {
                tile: index,
                got: first,
                expected: entry.start,
            });
        }
        let dense: Vec<u32> = tile.names.iter().map(|&n| self.piece(n)).collect();
        for (p, &v) in dense.iter().zip(&tile.volumes) {
            self.piece_volume[*p as usize] += v;
        }
        for &(a, b, parity) in &tile.relations {
            let (a, b) = (self.piece(a), self.piece(b));
            self.relations.push((a, b, parity));
        }
        for (t, &piece) in tile.triangles.iter().zip(&tile.piece) {
            let mut record = [0u8; RECORD];
            for (k, v) in t.iter().chain([dense[piece as usize]].iter()).enumerate() {
                record[4 * k..4 * k + 4].copy_from_slice(&v.to_le_bytes());
            }
            self.spool.write_all(&record).map_err(|e| self.io(e))?;
        }
        self.spooled += tile.triangles.len() as u64;
        Ok(())
    }

    fn piece(&mut self, name: u64) -> u32 {
        let next = self.piece_volume.len() as u32;
        let p = *self.pieces.entry(name).or_insert(next);
        if p == next {
            self.piece_volume.push(0.0);
        }
        p
    }

    /// Settles the orientation, replays the triangles and completes the
    /// file; returns the counts and the writer's audit.
    pub fn finish(mut self) -> Result<(StitchReport, MeshAudit), StitchError> {
        let pieces = self.piece_volume.len();
        let mut uf = ParityUnionFind::new(pieces);
        let mut contradictions = 0;
        for &(a, b, parity) in &self.relations {
            if !uf.union(a, b, parity) {
                let ((ra, pa), (rb, pb)) = (uf.find(a), uf.find(b));
                contradictions += u64::from(ra == rb && (pa ^ pb) != parity);
            }
        }
        let mut volume = vec![0.0f64; pieces];
        let mut root = Vec::with_capacity(pieces);
        for (p, &v) in self.piece_volume.iter().enumerate() {
            let (r, flip) = uf.find(p as u32);
            volume[r as usize] += if flip { -v } else { v };
            root.push((r, flip));
        }
        let flip_of: Vec<bool> = root
            .iter()
            .map(|&(r, flip)| flip ^ (volume[r as usize] < 0.0))
            .collect();
        self.spool.flush().map_err(|e| self.io(e))?;
        let file = self.spool.get_ref().try_clone().map_err(|e| self.io(e))?;
        // Relations that contradicted (a surface some job grew twisted
        // across a thin part) leave edges both triangles run the same way:
        // leave the later of each out, so the directed-edge promise holds.
        let mut same_way = SameWay::new(&self.spool_path, RunSizes::DEFAULT);
        replay(&self.spool_path, &file, self.spooled, &flip_of, |_, t| {
            same_way.add(t).map_err(|e| self.io(e))
        })?;
        let left_out = same_way.left_out().map_err(|e| self.io(e))?;
        let mut batch = Vec::with_capacity(1 << 16);
        let mut next_out = left_out.iter().peekable();
        let writer = &mut self.writer;
        replay(&self.spool_path, &file, self.spooled, &flip_of, |i, t| {
            if next_out.next_if_eq(&&i).is_some() {
                return Ok(());
            }
            batch.push(t);
            if batch.len() == batch.capacity() {
                writer.add_triangles(&batch)?;
                batch.clear();
            }
            Ok(())
        })?;
        self.writer.add_triangles(&batch)?;
        let written = self.writer.finish()?;
        let report = StitchReport {
            vertices: written.vertices,
            triangles: written.triangles,
            pieces: pieces as u64,
            contradictions,
            left_out: left_out.len() as u64,
        };
        Ok((report, written.audit))
    }
}

/// Reads the spooled triangles in order, each wound as its piece's flip
/// says, and hands each with its place to `each`.
fn replay(
    path: &Path,
    file: &File,
    spooled: u64,
    flip_of: &[bool],
    mut each: impl FnMut(u64, [u32; 3]) -> Result<(), StitchError>,
) -> Result<(), StitchError> {
    let mut reader = BufReader::with_capacity(1 << 20, file);
    let io = |e| StitchError::Io(IoError::os(path, e));
    reader.seek(SeekFrom::Start(0)).map_err(io)?;
    let mut record = [0u8; RECORD];
    for i in 0..spooled {
        reader.read_exact(&mut record).map_err(io)?;
        let word = |k: usize| {
            let b = &record[4 * k..4 * k + 4];
            u32::from_le_bytes([b[0], b[1], b[2], b[3]])
        };
        let t = [word(0), word(1), word(2)];
        each(
            i,
            if flip_of[word(3) as usize] {
                flipped(t)
            } else {
                t
            },
        )?;
    }
    Ok(())
}
