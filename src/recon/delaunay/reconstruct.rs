//! `reconstruct --method delaunay` end to end over a store: the tile kernel
//! (`super::kernel`), then the seam side: every tile's core points become
//! the output vertices (store order), its owned triangles go to a spool
//! (paged, with each one's signed volume) and their edges to an
//! out-of-core sort. At the end the edges give the mesh's dual edges, the
//! winding is decided over the whole surface flattest crossing first and
//! short twists are cut (`mesh::untwist`), and the spool is replayed into
//! the mesh writer, each triangle turned as the winding says; a component
//! whose long odd cycle cannot be wound (a Moebius band) is counted
//! non-orientable.
//!
//! An edge of more than two triangles (paper 4's fans on real scans leave
//! some: 204 on two depth-camera frames of a room, 16 on a city block)
//! keeps the two that continue each other most nearly flat, and the
//! others are left out (`mesh::fans`, out of core, over the whole stream,
//! so the choice is the same in any tiling); the two kept are then wound
//! like any other pair. A deviation from paper 4, which keeps multi-sheet
//! contacts: a mesh with a non-manifold edge is refused by most tools
//! downstream.
//!
//! Memory: the sorts' buffers and the paged arrays' caches
//! (`mesh::untwist::RESIDENT_BYTES`); the triangles, edges and sets wait on
//! disk.

use super::fan::{Hole, LOCAL_HOLE, OUTLIER, SPARSEST};
use super::kernel::{DelaunayKernel, DelaunayTile, BYTES_PER_POINT};
use super::scale::median_spacing;
use crate::memory::plan::MARGIN_FACTOR;
use crate::mesh::fans::Fans;
use crate::mesh::paged::Paged;
use crate::mesh::runs::RunSizes;
use crate::mesh::scratch::scratch_beside;
use crate::mesh::untwist::{self, Spooled, Untwist};
use crate::mesh::{MeshAudit, MeshError, MeshFormat, MeshWriter};
use crate::pipeline::{run_tiles, KernelCost, PipelineError, Progress, RunOptions, RunStats};
use crate::store::PointStore;
use glam::DVec3;
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
/// per loaded point; the seam side's caches and sort buffers whatever the
/// size; its triangles, edges and sets on disk.
pub fn cost() -> KernelCost {
    KernelCost {
        // The plan allows for MARGIN_FACTOR loaded points per core point.
        bytes_per_point: (BYTES_PER_POINT as f64 * LOADED_PER_CORE / MARGIN_FACTOR).ceil() as u64,
        global_per_point: 0,
        contracts_boundaries: false,
        resident_per_point: 0.0,
        window_bytes_per_point: 0,
        // Beside the store: the seam side's spool, edge uses, dual edges
        // and neighbours at their peak; the mesh is about two triangles
        // per input point (vertices are the input points).
        scratch_per_point: 2 * untwist::SCRATCH_PER_TRIANGLE,
        export_scratch_per_point: 2 * untwist::SCRATCH_PER_TRIANGLE,
        checkpoint_per_point: 0,
        external_scratch_saving: 0,
        export_frees_positions: false,
        output_per_point: 24 + 2 * 13,
        // The face spool and the audit beside the output, two triangles
        // per point.
        beside_output_per_point: (2.0 * crate::mesh::SCRATCH_BESIDE_OUTPUT_PER_TRIANGLE) as u64,
        parallel_in_tile: false,
        margin_spacings: 0.0,
        // `mesh::fans`' sort buffer fills beside the tiles; the winding's
        // caches and buffers after them (no more than the tiles held, but
        // freed tile memory may stay in the workers' allocator arenas).
        resident_bytes: (RunSizes::DEFAULT.chunk_bytes as u64).max(untwist::RESIDENT_BYTES),
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
    /// Triangles left out where a short odd cycle of triangles (a ring
    /// turned over round a hole) kept the surface from being wound
    /// (`mesh::untwist`).
    pub twists_cut: u64,
    /// Edges left unwound: each on an odd cycle longer than a twist (the
    /// surface's own, as a Moebius band's).
    pub unwound_edges: u64,
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
    /// The scratch files of the seam side could not be written or read.
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
    // After the tiles their memory is the seam side's.
    let room = opts
        .tile_room
        .or(opts.tile_bytes.map(|b| b * opts.in_flight as u64));
    let mut report = seam.finish(store, room)?;
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
    /// Every triangle as its tile listed it, with its signed volume.
    spool: Paged<Spooled>,
    /// Every triangle's edges, for the edges of more than two and the
    /// dual edges (taken at the end).
    fans: Fans,
    untwist: Untwist,
    report: DelaunayReport,
}

/// RAM of the spool's page cache (it is written and read in order).
const SPOOL_CACHE: usize = untwist::SMALL_CACHE;

impl Seams {
    fn new(writer: MeshWriter, output: &Path) -> Result<Self, DelaunayReconError> {
        Ok(Seams {
            writer,
            spool: Paged::new(scratch_beside(output)?, SPOOL_CACHE),
            fans: Fans::new(output, RunSizes::DEFAULT),
            untwist: Untwist::new(output)?,
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
        let mut ids = Vec::new();
        store.read_indices(entry.start, entry.count, &mut ids)?;
        self.untwist.add_ids(entry.start, &ids)?;
        for ((t, &normal), &volume6) in tile.tris.iter().zip(&tile.normals).zip(&tile.volumes) {
            let corners = t.map(|v| v as u32);
            self.spool
                .set(self.report.triangles, Spooled { corners, volume6 })?;
            self.fans.add(corners, normal)?;
            self.report.triangles += 1;
        }
        let r = &tile.report;
        let rep = &mut self.report;
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

    fn finish(
        self,
        store: &PointStore,
        room: Option<u64>,
    ) -> Result<DelaunayReport, DelaunayReconError> {
        let Seams {
            mut writer,
            mut spool,
            fans,
            mut untwist,
            mut report,
        } = self;
        let mut exact = Vec::new();
        let mended = fans.mend(
            |v| {
                store
                    .read_exact_in_store_order(u64::from(v), 1, &mut exact)
                    .map_err(std::io::Error::other)?;
                Ok(exact.first().copied().unwrap_or(DVec3::ZERO))
            },
            |twin| untwist.add(&twin),
        )?;
        report.non_manifold_mended = mended.edges;
        report.fins_left_out = mended.left_out.len() as u64;
        let mut winding = untwist.wind(report.triangles, &mended.left_out, &mut spool, room)?;
        report.twists_cut = winding.cut;
        report.unwound_edges = winding.unwound;
        report.components = winding.components;
        report.non_orientable = winding.non_orientable;
        let mut removed = std::mem::take(&mut winding.removed).into_iter().peekable();
        let mut batch = Vec::with_capacity(1 << 16);
        for index in 0..report.triangles {
            if removed.next_if_eq(&index).is_some() {
                continue;
            }
            let mut t = spool.get(index)?.corners;
            if winding.flip(index)? {
                t.swap(1, 2);
            }
            batch.push(t);
            if batch.len() == batch.capacity() {
                writer.add_triangles(&batch)?;
                batch.clear();
            }
        }
        writer.add_triangles(&batch)?;
        let written = writer.finish()?;
        (report.vertices, report.triangles) = written.counts();
        report.audit = written.audit;
        Ok(report)
    }
}
