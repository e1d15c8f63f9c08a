//! `reconstruct --method delaunay` end to end over a store: the tile kernel
//! (`super::kernel`), then the seam side: every tile's core points become
//! the output vertices (store order), its owned triangles go to a spool
//! with a global component number, and seam edges met from both sides join
//! components in a parity union-find (the two triangles must run the edge
//! in opposite directions). At the end each component's flip is known and
//! the spool is replayed into the mesh writer; a component whose parities
//! contradict each other is non-orientable (a Moebius band) and is counted.
//!
//! An edge of more than two triangles (paper 4's fans on real scans leave
//! some: 204 on two depth-camera frames of a room, 16 on a city block)
//! keeps the two that continue each other most nearly flat, and the
//! others are left out (`mesh::fans`, out of core, over the whole stream,
//! so the choice is the same in any tiling); the two kept then join their
//! components like a seam edge, so they are wound consistently. A
//! deviation from paper 4, which keeps multi-sheet contacts: a mesh with a
//! non-manifold edge is refused by most tools downstream.
//!
//! Memory: the seam edges waiting for their twin (about the tiles' borders;
//! a tile sends only edges whose twin another tile owns, so each meets
//! it), one union-find entry per tile component; the triangles wait on
//! disk.

use super::fan::{Hole, LOCAL_HOLE, OUTLIER, SPARSEST};
use super::kernel::{DelaunayKernel, DelaunayTile, BYTES_PER_POINT};
use super::scale::median_spacing;
use crate::memory::plan::MARGIN_FACTOR;
use crate::mesh::fans::{Fans, Mended};
use crate::mesh::runs::RunSizes;
use crate::mesh::{MeshAudit, MeshError, MeshFormat, MeshWriter};
use crate::normals::unionfind::ParityUnionFind;
use crate::pipeline::{run_tiles, KernelCost, PipelineError, Progress, RunOptions, RunStats};
use crate::store::PointStore;
use glam::DVec3;
use std::collections::HashMap;
use std::io::{BufReader, BufWriter, Read, Seek, Write};
use std::path::Path;

/// Margin first loaded, in store spacings: the doubt from the loaded
/// region's faces reaches about 90 spacings in on the noisy dragon (the
/// fans' proofs about 35, the deletion rounds 27, the pieces and patches
/// 25 since patches read four rings round their loop), and the kernel asks
/// for 1.25 times that when short. At 90 the 1M dragon reloaded 5 of 8
/// tiles (44 s); at 110, 1 (32 s).
const MARGIN_SPACINGS: f64 = 110.0;

/// Loaded points per core point a tile's first load holds (measured on
/// the 3M noisy dragon with 94k-point cores: 1.6 to 2.6); the plan sizes
/// tiles for it, and a reload that loads more waits for the memory of
/// more tiles (`pipeline::shares`).
const LOADED_PER_CORE: f64 = 2.6;

/// What the run costs (ARCHITECTURE.md, memory model): the kernel's bytes
/// per loaded point and nothing per stored point beyond the seam side's
/// map (seam-sized) and one union-find entry per tile component.
pub fn cost() -> KernelCost {
    KernelCost {
        // The plan allows for MARGIN_FACTOR loaded points per core point.
        bytes_per_point: (BYTES_PER_POINT as f64 * LOADED_PER_CORE / MARGIN_FACTOR).ceil() as u64,
        global_per_point: 0,
        contracts_boundaries: false,
        resident_per_point: 0.0,
        window_bytes_per_point: 0,
        // Beside the store: the mesh spool and the edge uses of
        // `mesh::fans` (three of 24 B per triangle); the mesh is about two
        // triangles per input point (vertices are the input points).
        scratch_per_point: 2 * 12 + 2 * 3 * 24,
        output_per_point: 24 + 2 * 13,
        // The face spool and the audit beside the output, two triangles
        // per point.
        beside_output_per_point: (2.0 * crate::mesh::SCRATCH_BESIDE_OUTPUT_PER_TRIANGLE) as u64,
        parallel_in_tile: false,
        margin_spacings: 0.0,
        // `mesh::fans`' sort buffer fills beside the tiles; its merge runs
        // after them.
        resident_bytes: RunSizes::DEFAULT.chunk_bytes as u64,
    }
}

/// Parameters of the Delaunay-based (paper 4) reconstruction.
#[derive(Clone, Copy, Debug, Default)]
pub struct DelaunayParams {
    /// Absolute hole radius; default: `Hole::Local` with `LOCAL_HOLE`.
    pub hole: Option<f64>,
}

impl DelaunayParams {
    /// Refuses a hole radius that is not positive and finite.
    pub fn validate(&self) -> Result<(), DelaunayReconError> {
        match self.hole {
            Some(h) if !(h.is_finite() && h > 0.0) => Err(DelaunayReconError::BadHole(h)),
            _ => Ok(()),
        }
    }
}

/// What the Delaunay-based reconstruction did.
#[derive(Clone, Debug, Default)]
pub struct DelaunayReport {
    /// Points of the store.
    pub points: u64,
    /// Vertices of the mesh written.
    pub vertices: u64,
    /// Triangles of the mesh written.
    pub triangles: u64,
    /// Connected components of the mesh.
    pub components: u64,
    /// Components that could not be wound consistently (non-orientable).
    pub non_orientable: u64,
    /// Input points that repeat another point's coordinates, left out of the triangulations.
    pub duplicates: u64,
    /// Incompatible triangles deleted as type 1 (paper 4 section 2.3).
    pub type1: u64,
    /// Incompatible triangles deleted as type 2.
    pub type2: u64,
    /// Triangles deleted by the forced choice at incompatible edges.
    pub forced: u64,
    /// Triangles added to close small holes.
    pub patches: u64,
    /// Incompatible edges left after the last cleanup round.
    pub incompatible_left: u64,
    /// Edges that had more than two triangles, and the triangles left out
    /// so that each keeps two (see the module doc).
    pub non_manifold_mended: u64,
    /// Triangles left out at edges of more than two.
    pub fins_left_out: u64,
    /// Largest triangulation of a tile, bytes per loaded point.
    pub triangulation_bytes_per_point: f64,
    /// The hole-closing rule used, for the report.
    pub hole: String,
    /// The mesh written: its edges, vertices, components and volumes
    /// (counted only: the method promises nothing it does not build).
    pub audit: MeshAudit,
    /// Tiles, retries and margins of the run.
    pub run: RunStats,
}

/// Errors of the Delaunay-based reconstruction.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum DelaunayReconError {
    /// The tile pipeline failed.
    #[error(transparent)]
    Pipeline(#[from] PipelineError),
    /// Writing the mesh failed.
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// The hole radius given is zero, negative or not finite.
    #[error("hole radius {0} must be a positive finite number")]
    BadHole(f64),
    /// The store holds more points than a PLY index can name.
    #[error("{points} points: more than the 2^31 vertices a PLY index holds")]
    TooManyPoints {
        /// Points of the store.
        points: u64,
    },
    /// Reading the store failed.
    #[error(transparent)]
    Store(#[from] crate::store::StoreError),
    /// The scratch file of the seam triangles could not be written or read.
    #[error("triangle spool: {0}")]
    Spool(#[from] std::io::Error),
}

impl DelaunayReconError {
    /// The mesh layer's error inside, when writing the mesh is what failed
    /// (a broken promise carries the audit and names the incomplete file).
    pub fn mesh(&self) -> Option<&MeshError> {
        match self {
            DelaunayReconError::Mesh(e) => Some(e),
            _ => None,
        }
    }
}

/// Reconstructs a mesh from the points of `store` with paper 4's Delaunay-based method, tile by tile, writing it to `output` in `format`; tiled output equals untiled.
pub fn reconstruct_delaunay(
    store: &mut PointStore,
    params: &DelaunayParams,
    output: &Path,
    format: MeshFormat,
    opts: RunOptions,
    progress: &dyn Progress,
) -> Result<DelaunayReport, DelaunayReconError> {
    params.validate()?;
    if store.len() > i32::MAX as u64 {
        return Err(DelaunayReconError::TooManyPoints {
            points: store.len(),
        });
    }
    // The estimate samples tiles: it sets the first margin (time), never
    // a result (ARCHITECTURE.md).
    let spacing = crate::store::spacing::ensure_spacing(store)?;
    let store = &*store;
    let hole = match params.hole {
        Some(h) => Hole::Absolute(h),
        None => {
            let median = median_spacing(store, spacing, opts, progress)?;
            Hole::Local {
                multiple: LOCAL_HOLE,
                ceiling: median.map_or(f64::INFINITY, |m| SPARSEST * m),
            }
        }
    };
    let kernel = DelaunayKernel {
        hole,
        initial_margin: MARGIN_SPACINGS * spacing,
        store: Some(store),
    };
    let mut seam = Seams::new(MeshWriter::create(output, format)?, output)?;
    let run = run_tiles(store, &kernel, opts, progress, |t, out| {
        seam.add_tile(store, t, out).map_err(PipelineError::seam)
    })?;
    let mut report = seam.finish(store)?;
    report.run = run;
    report.points = store.len();
    report.hole = match hole {
        Hole::Absolute(h) => format!("{h:.4e}"),
        Hole::Local { multiple, ceiling } => format!(
            "{multiple} x the largest spacing of a triangle's corners (nearest-neighbour distance, at most {OUTLIER} x the neighbour's and at most {ceiling:.4e}, {SPARSEST} x the median spacing)"
        ),
    };
    Ok(report)
}

/// The seam side of the run (see the module doc).
struct Seams {
    writer: MeshWriter,
    spool: BufWriter<std::fs::File>,
    /// Every triangle's edges, for the edges of more than two (taken at
    /// the end).
    fans: Option<Fans>,
    /// Edge (low, high store index) -> component and whether it runs low
    /// to high in its triangle.
    waiting: HashMap<(u64, u64), (u32, bool)>,
    joins: Vec<(u32, u32, bool)>,
    inconsistent: Vec<bool>,
    /// Per global component: six times its signed volume as the tile
    /// wound it, about the store origin.
    volumes: Vec<f64>,
    report: DelaunayReport,
}

impl Seams {
    fn new(writer: MeshWriter, output: &Path) -> Result<Self, DelaunayReconError> {
        Ok(Seams {
            writer,
            spool: BufWriter::new(tempfile::tempfile()?),
            fans: Some(Fans::new(output, RunSizes::DEFAULT)),
            waiting: HashMap::new(),
            joins: Vec::new(),
            inconsistent: Vec::new(),
            volumes: Vec::new(),
            report: DelaunayReport::default(),
        })
    }

    /// Tile `t`'s vertices (its core points: the input's own coordinates,
    /// in store order) and its triangles.
    fn add_tile(
        &mut self,
        store: &PointStore,
        t: usize,
        tile: DelaunayTile,
    ) -> Result<(), DelaunayReconError> {
        let entry = &store.tiles()[t];
        let mut vertices = Vec::new();
        store.read_exact_in_store_order(entry.start, entry.count, &mut vertices)?;
        self.writer.add_vertices(&vertices)?;
        let base = self.inconsistent.len() as u32;
        self.inconsistent.extend_from_slice(&tile.inconsistent);
        self.volumes.extend_from_slice(&tile.volumes);
        for (t, c) in tile.tris.iter().zip(&tile.component) {
            for v in t {
                self.spool.write_all(&(*v as u32).to_le_bytes())?;
            }
            self.spool.write_all(&(base + c).to_le_bytes())?;
            if let Some(fans) = &mut self.fans {
                fans.add(t.map(|v| v as u32), base + c)?;
            }
        }
        for (a, b, c) in tile.seams {
            let key = (a.min(b), a.max(b));
            let forward = a < b;
            match self.waiting.remove(&key) {
                // Consistent when the two run the edge in opposite ways.
                Some((other, dir)) => self.joins.push((other, base + c, dir == forward)),
                None => {
                    self.waiting.insert(key, (base + c, forward));
                }
            }
        }
        let r = &tile.report;
        let rep = &mut self.report;
        rep.triangles += tile.tris.len() as u64;
        rep.duplicates += r.duplicates;
        rep.type1 += r.cleanup.type1;
        rep.type2 += r.cleanup.type2;
        rep.forced += r.cleanup.forced;
        rep.patches += r.patches;
        rep.incompatible_left += r.cleanup.incompatible_left;
        let loaded = (r.cells as f64 / 6.5).max(1.0);
        rep.triangulation_bytes_per_point = rep
            .triangulation_bytes_per_point
            .max(r.triangulation_bytes as f64 / loaded);
        Ok(())
    }

    fn finish(mut self, store: &PointStore) -> Result<DelaunayReport, DelaunayReconError> {
        let mut exact = Vec::new();
        let mended = match self.fans.take() {
            Some(fans) => fans.mend(|v| {
                store
                    .read_exact_in_store_order(u64::from(v), 1, &mut exact)
                    .map_err(std::io::Error::other)?;
                Ok(exact.first().copied().unwrap_or(DVec3::ZERO))
            })?,
            None => Mended::default(),
        };
        self.report.non_manifold_mended = mended.edges;
        self.report.fins_left_out = mended.left_out.len() as u64;
        self.joins.extend(mended.pairs.iter().copied());
        let n = self.inconsistent.len();
        let mut uf = ParityUnionFind::new(n);
        let mut bad = self.inconsistent.clone();
        for &(a, b, parity) in &self.joins {
            let ((ra, pa), (rb, pb)) = (uf.find(a), uf.find(b));
            if ra == rb {
                if pa ^ pb != parity {
                    bad[ra as usize] = true;
                }
            } else {
                let carried = bad[ra as usize] || bad[rb as usize];
                uf.union(a, b, parity);
                let root = uf.find(a).0;
                bad[root as usize] |= carried;
            }
        }
        let mut roots = vec![false; n];
        for c in 0..n as u32 {
            let (r, _) = uf.find(c);
            if !roots[r as usize] {
                roots[r as usize] = true;
                self.report.components += 1;
                self.report.non_orientable += bad[r as usize] as u64;
            }
        }
        let flips = outward(&mut uf, &self.volumes);
        self.replay(&flips, &mended.left_out)?;
        let written = self.writer.finish()?;
        (self.report.vertices, self.report.triangles) = written.counts();
        self.report.audit = written.audit;
        Ok(self.report)
    }

    /// Writes the spooled triangles but those `left_out` (places,
    /// increasing), each component flipped as `flips` says.
    fn replay(&mut self, flips: &[bool], left_out: &[u64]) -> Result<(), DelaunayReconError> {
        self.spool.flush()?;
        let mut file = self.spool.get_ref().try_clone()?;
        file.rewind()?;
        let mut reader = BufReader::with_capacity(1 << 20, file);
        let mut record = [0u8; 16];
        let mut batch = Vec::with_capacity(1 << 16);
        let mut out = left_out.iter().peekable();
        for index in 0..self.report.triangles {
            reader.read_exact(&mut record)?;
            if out.next_if_eq(&&index).is_some() {
                continue;
            }
            let w = |k: usize| {
                u32::from_le_bytes([
                    record[4 * k],
                    record[4 * k + 1],
                    record[4 * k + 2],
                    record[4 * k + 3],
                ])
            };
            let mut t = [w(0), w(1), w(2)];
            if flips[w(3) as usize] {
                t.swap(1, 2);
            }
            batch.push(t);
            if batch.len() == batch.capacity() {
                self.writer.add_triangles(&batch)?;
                batch.clear();
            }
        }
        self.writer.add_triangles(&batch)?;
        Ok(())
    }
}

/// Whether each tile component is flipped: as its parity to its root says,
/// and the whole root once more when its signed volume, summed over its
/// components as they will be written, is negative. A closed surface then
/// faces outward (paper 4 leaves the result unoriented; the audit found
/// the torus wound inward); an open one faces away from the store origin,
/// the projection method's convention (`recon::projection::orient`).
fn outward(uf: &mut ParityUnionFind, volumes: &[f64]) -> Vec<bool> {
    let mut total = vec![0.0f64; volumes.len()];
    let parity: Vec<(u32, bool)> = (0..volumes.len() as u32).map(|c| uf.find(c)).collect();
    for (&(root, flip), &v) in parity.iter().zip(volumes) {
        total[root as usize] += if flip { -v } else { v };
    }
    parity
        .iter()
        .map(|&(root, flip)| flip ^ (total[root as usize] < 0.0))
        .collect()
}
