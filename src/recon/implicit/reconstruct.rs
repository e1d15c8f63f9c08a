//! `reconstruct --method implicit` end to end over a store: oriented normals
//! (computed unless the store has them), paper 1's rho and delta, one global
//! lattice anchored at the store origin, the marching-cubes tile kernel, and
//! the seam stitcher streaming into a mesh file (through a filter of small
//! pieces). With `--closed` every lattice corner gets a sign
//! (`closed`) and the run promises a closed surface: the
//! writer's audit checks it.

use super::blocks::BLOCK;
use super::closed::{self, Everywhere};
use super::field::Field;
use super::follow::FOLLOW_STEPS;
use super::kernel::ImplicitKernel;
use super::lattice::{Lattice, LatticeError};
use super::stitch::Stitcher;
use super::winding::cells::gather_store;
use crate::mesh::{
    MeshAudit, MeshError, MeshFormat, MeshWriter, PieceFilter, PieceReport, Promise,
};
use crate::normals::{ensure_normals, NormalParams, NormalsError, NormalsReport};
use crate::normals::{FLAG_DEGENERATE, FLAG_UNORIENTED};
use crate::pipeline::{run_tiles, KernelCost, PipelineError, Progress, RunOptions, RunStats};
use crate::store::{PointStore, StoreError};
use crate::tiling::load::core_box;
use glam::DVec3;
use std::path::Path;

/// Parameters of the implicit (paper 1) reconstruction; lengths in the
/// points' units.
#[derive(Clone, Copy, Debug, Default)]
pub struct ImplicitParams {
    /// The normals to compute first when the store has none (or other ones).
    pub normals: NormalParams,
    /// Cube edge; default rho + delta (paper 1 section 2.6).
    pub cell: Option<f64>,
    /// Noise bound delta; default estimated from the plane-fit residuals.
    pub noise: Option<f64>,
    /// The surface is closed: every corner is defined (paper 1 section 4.1).
    pub closed: bool,
    /// Drop connected pieces with fewer triangles than this share of the
    /// largest piece's; default `CLOSED_MIN_PIECE` with `closed`, else 0.
    pub min_piece: Option<f64>,
    /// The signed distance (default: moving least squares).
    pub field: Field,
    /// How far from the new triangles a vertex a flat block leaves out may
    /// lie, in mean spacings ([`super::blocks`]); default
    /// [`FLAT_TOLERANCE_SPACINGS`], 0 keeps every marching-cubes triangle.
    pub flat_tolerance: Option<f64>,
}

/// The default [`ImplicitParams::flat_tolerance`], in mean spacings: 0,
/// every marching-cubes triangle kept. Merging helps one kind of surface
/// and costs another: on the 1M noisy terrain (two seeds) 0.1 spacings
/// halves the triangles and lowers the mean distance to the truth (0.0380
/// -> 0.0369, 0.0378 -> 0.0368 spacings), while on the 1M noisy dragon it
/// takes 18 % of them and raises the mean (0.0503 -> 0.0515); at 0.02 the
/// dragon keeps its figure but the terrain loses 8 % of its triangles and
/// 0.0002 spacings of accuracy. So the user chooses, per scan.
pub const FLAT_TOLERANCE_SPACINGS: f64 = 0.0;

impl ImplicitParams {
    /// The `min_piece` share to use (its default filled in), or why it is
    /// unusable.
    pub fn min_piece_share(&self) -> Result<f64, ReconError> {
        let default = if self.closed { CLOSED_MIN_PIECE } else { 0.0 };
        let share = self.min_piece.unwrap_or(default);
        if (0.0..=1.0).contains(&share) {
            Ok(share)
        } else {
            Err(ReconError::BadShare(share))
        }
    }
}

/// Mesh triangles per input point at a cell of 2.2 mean spacings, allowed
/// for when planning the small-piece filter's page tables, the scratch
/// disk and the output's size; a surface has about `(2.2 / cell)^2` as many
/// at other cells. Measured (open, default cell): the 1M noisy dragon
/// 2.38, the 1M terrain 1.77, a 110k aerial LAS (autzen) 1.96, a
/// depth-camera pair 1.90; at 3 and 6 spacings the dragon 1.28 and 0.32
/// (the rule gives 1.28 and 0.32). A 5.7k forest plot had 3.47: sparse
/// scans of many small surfaces exceed it.
const TRIANGLES_PER_POINT_AT_2_2: f64 = 2.5;

/// With `--closed` an open scan (a terrain, a town) closes into a slab,
/// top and bottom: about twice the triangles (terrain 1.91, autzen 1.93
/// per point at 3 spacings where the open rule gives 0.95 and 1.05).
const CLOSED_SLAB: f64 = 2.0;

/// Scratch bytes per mesh triangle in the run directory: the marching
/// cubes' checkpointed tile outputs. Measured with the run directory's
/// size sampled every 50 ms: peak = store + 48 + 100.5 x triangles per
/// point on the 1M dragon (open at 2.2 and 6 spacings, `--closed`), the 1M
/// terrain and a 110k LAS, each within 3 %.
const SCRATCH_PER_TRIANGLE: f64 = 101.0;
/// Scratch bytes per point beside the store during marching cubes (the
/// normals and flags columns and the normals' checkpointed tiles).
const SCRATCH_BEFORE_TRIANGLES: u64 = 48;
/// Output bytes per triangle: half a vertex (24 B) and a face (13 B).
const OUTPUT_PER_TRIANGLE: f64 = 25.0;
/// Scratch bytes per point beside the store while a plain run meshes and
/// writes: the normals and flags columns the marching cubes read. The
/// orientation's scratch is gone by then; counting it (44 B, as this plan
/// did) refused the 1B dragon at 6 spacings for 70.8 GiB where 100M had
/// measured 42 B a point beside its store at the peak, output included.
const COLUMNS_WHILE_MESHING: u64 = 13;

/// Peak bytes of a band cube ([`super::kernel`]'s measurements).
fn bytes_per_cube(closed: bool) -> u64 {
    match closed {
        true => super::kernel::BYTES_PER_CUBE_CLOSED,
        false => super::kernel::BYTES_PER_CUBE,
    }
}

impl ImplicitParams {
    /// The lattice cell in mean spacings the plan assumes (the MLS field's).
    /// Triangles per input point to plan for, at the default cell (a
    /// `--cell` given in the input's units is not known in spacings before
    /// the store is built; the memory plan then assumes the default).
    fn triangles_per_point(&self) -> f64 {
        self.triangles_at(self.cell_spacings())
    }

    /// Triangles per input point at a cell of `cell_spacings` spacings.
    fn triangles_at(&self, cell_spacings: f64) -> f64 {
        let slab = if self.closed { CLOSED_SLAB } else { 1.0 };
        TRIANGLES_PER_POINT_AT_2_2 * slab * (2.2 / cell_spacings.max(0.1)).powi(2)
    }

    fn cell_spacings(&self) -> f64 {
        match self.closed {
            true => CLOSED_MLS_CELL_SPACINGS,
            false => MLS_CELL_SPACINGS,
        }
    }

    /// What a reconstruction costs, for the memory plan: the normals run's
    /// cost, plus the small-piece filter's page tables when pieces are
    /// dropped (its per-vertex state is in scratch files behind caches of a
    /// fixed 16 MiB, within the fixed costs: the read chunk and the
    /// histogram are gone by then).
    pub fn cost(&self) -> KernelCost {
        self.cost_for(None)
    }

    /// [`Self::cost`] once the store's mean spacing is known: a `--cell`
    /// given in the input's units is then known in spacings, and the disk
    /// plan counts the mesh's share at that cell.
    pub fn cost_with_spacing(&self, spacing: f64) -> KernelCost {
        self.cost_for(Some(spacing))
    }

    fn cost_for(&self, spacing: Option<f64>) -> KernelCost {
        let triangles = self.triangles_per_point();
        // A `--cell` in the input's units is not known in spacings before
        // the store is built: the disk plan then leaves the mesh's share
        // out rather than refuse a coarse run by the default cell's count.
        let on_disk = match (self.cell, spacing) {
            (None, _) => triangles,
            (Some(cell), Some(sp)) if cell > 0.0 && sp > 0.0 => self.triangles_at(cell / sp),
            (Some(_), _) => 0.0,
        };
        let pieces = self.min_piece_share().unwrap_or(0.0) > 0.0;
        let normals = self.normals.cost();
        let marching = super::kernel::planned_bytes_per_loaded_point(
            self.cell_spacings(),
            bytes_per_cube(self.closed),
        );
        KernelCost {
            bytes_per_point: normals.bytes_per_point.max(marching),
            resident_per_point: if pieces {
                triangles / 2.0 * crate::mesh::pieces::BYTES_PER_VERTEX
            } else {
                0.0
            },
            // A plain run streams each tile's triangles to the writer
            // (its spool is beside the output): the normals' scratch is
            // the peak. A run directory keeps the tiles' triangles too.
            scratch_per_point: normals.scratch_per_point,
            export_scratch_per_point: COLUMNS_WHILE_MESHING,
            // A run directory's peak beside the store, over the export's
            // columns: `in_run_dir` adds it to both phases, so the stages'
            // phase is planned 31 B a point above its own peak there.
            checkpoint_per_point: (normals.scratch_per_point + normals.checkpoint_per_point)
                .max(SCRATCH_BEFORE_TRIANGLES + (on_disk * SCRATCH_PER_TRIANGLE) as u64)
                - COLUMNS_WHILE_MESHING,
            external_scratch_saving: normals.external_scratch_saving,
            export_frees_positions: false,
            output_per_point: (on_disk * OUTPUT_PER_TRIANGLE).ceil() as u64,
            beside_output_per_point: (on_disk * crate::mesh::SCRATCH_BESIDE_OUTPUT_PER_TRIANGLE)
                as u64,
            parallel_in_tile: false,
            margin_spacings: 0.0,
            resident_bytes: match self.closed {
                true => super::winding::cells::MAX_TREE_BYTES,
                false => 0,
            },
            ..normals
        }
    }
}

/// Default share of the largest piece below which `--closed` drops a piece:
/// a closed scan is of objects, and a piece with a hundredth of the main
/// one's triangles is a stray cluster closed on itself (the 10M dragon's
/// ten are 4 to 258 triangles beside 2.8 million).
pub(crate) const CLOSED_MIN_PIECE: f64 = 0.01;

/// What the implicit reconstruction did.
#[derive(Clone, Copy, Debug, Default)]
pub struct ImplicitReport {
    /// Present when this run computed the normals.
    pub normals: Option<NormalsReport>,
    /// Points of the store.
    pub points: u64,
    /// Paper 1's sampling density `rho` (section 2.6).
    pub rho: f64,
    /// Points whose nearest neighbour lies beyond what `rho` admits.
    pub rho_outliers: u64,
    /// Paper 1's noise bound `delta`.
    pub delta: f64,
    /// Side of the lattice cubes used.
    pub cell: f64,
    /// Vertices of the mesh written.
    pub vertices: u64,
    /// Triangles of the mesh written.
    pub triangles: u64,
    /// Cubes whose corners the field was asked for, over all tiles (the
    /// surface walk's when open, the band's with `--closed`).
    pub cubes: u64,
    /// With `--closed`: triangles drawn in cubes a corner of which the
    /// winding number decided, away from the data (holes closed, and the
    /// band's edge wherever the field and the winding number disagree:
    /// a large share says the normals are wrong somewhere).
    pub away_triangles: u64,
    /// Triangles fewer after flat blocks were re-triangulated
    /// (`flat_tolerance`).
    pub merged_triangles: u64,
    /// Small pieces dropped.
    pub pieces: PieceReport,
    /// The mesh written: its edges, vertices, components and volumes.
    pub audit: MeshAudit,
    /// Seam entries left at the end (0: the seam maps forgot every vertex
    /// once complete).
    pub seam_left: u64,
    /// Tiles, retries and margins of the run.
    pub run: RunStats,
}

/// Errors of the implicit reconstruction.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ReconError {
    /// Computing the normals failed, or their parameters are unusable.
    #[error(transparent)]
    Normals(#[from] NormalsError),
    /// The tile pipeline failed.
    #[error(transparent)]
    Pipeline(#[from] PipelineError),
    /// Reading the store failed.
    #[error(transparent)]
    Store(#[from] StoreError),
    /// Writing the mesh failed.
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// The lattice could not be laid or polygonised.
    #[error(transparent)]
    Lattice(#[from] LatticeError),
    /// A length is out of range (the cell not positive, the noise bound negative, or either not finite).
    #[error("{what} {value} is out of range: a cell must be positive, a noise bound at least 0, both finite")]
    BadParameter {
        /// Which length: `cell` or `noise`.
        what: &'static str,
        /// The value given or estimated.
        value: f64,
    },
    /// The flat blocks' tolerance is negative or not finite.
    #[error("flat tolerance {0} spacings must be finite and at least 0")]
    BadFlatTolerance(f64),
    /// The small-piece share lies outside `[0, 1]`.
    #[error("small-piece share {0} must lie between 0 and 1")]
    BadShare(f64),
}

impl ReconError {
    /// The mesh layer's error inside, when writing the mesh is what failed
    /// (a broken promise carries the audit and names the incomplete file).
    pub fn mesh(&self) -> Option<&MeshError> {
        match self {
            ReconError::Mesh(e) => Some(e),
            _ => None,
        }
    }
}

/// Reconstructs a mesh from the points of `store` with paper 1's implicit
/// method (normals first when the store has none), tile by tile, writing it
/// to `output` in `format`; tiled output equals untiled.
pub fn reconstruct_implicit(
    store: &mut PointStore,
    params: &ImplicitParams,
    output: &Path,
    format: MeshFormat,
    opts: RunOptions,
    progress: &dyn Progress,
) -> Result<ImplicitReport, ReconError> {
    params.validate()?;
    let min_piece = params.min_piece_share()?;
    let mut report = ImplicitReport {
        normals: ensure_normals(store, &params.normals, opts, progress)?,
        ..ImplicitReport::default()
    };
    report.points = store.len();
    let stats = store.manifest().sampling.unwrap_or_default();
    report.rho = if stats.rho > 0.0 {
        stats.rho
    } else {
        store.manifest().spacing.unwrap_or(1.0)
    };
    report.rho_outliers = stats.rho_outliers;
    report.delta = positive("noise", params.noise.unwrap_or(stats.noise), true)?;
    let spacing = if stats.mean_nn > 0.0 {
        stats.mean_nn
    } else {
        report.rho
    };
    report.cell = positive(
        "cell",
        params.cell.unwrap_or(default_cell(
            params.field,
            params.closed,
            spacing,
            report.rho + report.delta,
        )),
        false,
    )?;
    let band = band_cubes(params.field, spacing, report.cell);
    let lattice = Lattice::new(DVec3::ZERO, report.cell)?;
    let reach = report.rho + report.delta;
    let mut kernel = ImplicitKernel {
        lattice,
        limit: if params.closed { f64::INFINITY } else { reach },
        // The surface walk's reach (the band and its steps) beyond the core.
        initial_margin: (band + FOLLOW_STEPS + BLOCK) as f64 * report.cell + 2.0 * reach,
        band,
        field: params.field,
        spacing,
        bytes_per_cube: bytes_per_cube(params.closed),
        everywhere: None,
        flat_tolerance: params.flat_tolerance.unwrap_or(FLAT_TOLERANCE_SPACINGS) * spacing,
    };
    if params.closed {
        kernel.everywhere = Some(everywhere(store, &kernel)?);
        kernel.initial_margin = (closed::COARSE + 5 + BLOCK) as f64 * report.cell + 2.0 * reach;
    }
    // A closed surface is watertight, manifold, consistently wound and
    // encloses a positive volume in every piece; a mesh that is not is
    // written as incomplete and the run fails (`Promise`).
    let promise = match params.closed {
        true => Promise::CLOSED,
        false => Promise::NOTHING,
    };
    let out = MeshWriter::create(output, format)?.promising(promise);
    let writer = PieceFilter::new(out, min_piece)?;
    let cores = store.tiles().iter().map(|t| core_box(store, t)).collect();
    let mut stitcher = Stitcher::new(writer, store.origin(), cores);
    let shared = &*store;
    report.run = run_tiles(shared, &kernel, opts, progress, |t, out| {
        report.cubes += out.cubes as u64;
        report.away_triangles += out.away as u64;
        report.merged_triangles += out.merged as u64;
        let core = core_box(shared, &shared.tiles()[t]);
        stitcher
            .add_tile(&lattice, (t, &core), &out.triangles)
            .map_err(PipelineError::seam)
    })?;
    // Every tile is meshed: the output is written from their triangles
    // alone, and a scratch store's points would sit beside it.
    store.release_points()?;
    let written = stitcher.finish()?;
    report.vertices = written.vertices;
    report.triangles = written.triangles;
    report.pieces = written.pieces;
    report.audit = written.audit;
    report.seam_left = written.seam_left;
    Ok(report)
}

/// Side of the winding tree's leaves, in cubes: a leaf of the default
/// `--closed` cell (3 spacings) then holds about 9 samples of a random
/// sampling, enough for a spread ([`super::winding::cells`]), and the
/// corners that ask lie at least one and a half leaves from the samples.
const LEAF_CUBES: f64 = 2.0;

/// The signs away from the samples for `--closed`: the samples' winding
/// tree, in leaves of [`LEAF_CUBES`], over the store's box padded beyond the
/// band and two coarse cells.
fn everywhere(store: &PointStore, kernel: &ImplicitKernel) -> Result<Everywhere, ReconError> {
    let unusable = match kernel.takes_islands() {
        true => FLAG_DEGENERATE,
        false => FLAG_DEGENERATE | FLAG_UNORIENTED,
    };
    let leaf = LEAF_CUBES * kernel.lattice.cell;
    let tree = gather_store(store, leaf, kernel.spacing, unusable)?;
    let pad = kernel.band + 2 * closed::COARSE + 2;
    Ok(Everywhere::new(
        tree,
        &kernel.lattice,
        &store.relative_bounds(),
        pad,
    ))
}

/// Lattice cell of the MLS field in open mode, in spacings (mean
/// nearest-neighbour distances). Its vertices lie on the field's zero set
/// whatever the cell, so the cell only sets how finely the mesh follows
/// curvature (the chord error, about L^2 / 8R for edges L on radius R).
/// 1M noisy dragon, mean distance to the true surface both ways at cells of
/// 3 / 2.2 / 1.8 spacings: 0.0572 / 0.0541 / 0.0535 (Open3D Poisson depth
/// 9: 0.0723), the time about inversely proportional to the cell squared.
pub(crate) const MLS_CELL_SPACINGS: f64 = 2.2;

/// The MLS cell with `closed`, in spacings: coarser than the open one.
/// It was set so when holes were patched after marching cubes, because a
/// finer lattice met holes no least-area patch fitted (the 1M dragon at
/// 3 / 2.2 spacings left 0 / 4 open); every corner now has a sign
/// ([`super::closed`]), so that reason is gone, and 3 stays for the time
/// (the time grows as 1 / cell^2; `--cell` gives the finer mesh).
pub(crate) const CLOSED_MLS_CELL_SPACINGS: f64 = 3.0;

/// The default cell: paper 1's `rho + delta` (section 2.6) for its own
/// field; [`MLS_CELL_SPACINGS`] (open) or [`CLOSED_MLS_CELL_SPACINGS`] for
/// the MLS field.
///
/// Deviation for the MLS field: `rho` is the *largest* nearest-neighbour
/// distance (7 spacings on the dragon), coarse enough that the chord error
/// (0.14 spacings on the dragon) swamps the field's accuracy.
fn default_cell(field: Field, closed: bool, spacing: f64, paper: f64) -> f64 {
    match (field, closed) {
        (Field::Mls, false) => MLS_CELL_SPACINGS * spacing,
        (Field::Mls, true) => CLOSED_MLS_CELL_SPACINGS * spacing,
        (Field::Paper1, _) => paper,
    }
}

/// Half-width of the band of cubes around the samples, in spacings. The
/// band is where the surface can appear, so it must reach across the
/// sparsest sampling (terrain far from the scanner: the test terrain at a
/// cell of 3 spacings has 34 holes with a band of 1 cube, 0 with 2). Six
/// spacings keeps the reach the 3-spacing cell had (two cubes) at the open
/// cell of 2.2: with four, the test terrain opened a second boundary loop.
/// With `--closed` the band is where the field's value rather than the
/// winding number's decides ([`super::closed`]).
const BAND_SPACINGS: f64 = 6.0;

/// The band's reach in cubes: one for paper 1's field (its cell is
/// `rho + delta`), else at least one, the half-width above when the cell
/// is finer.
fn band_cubes(field: Field, spacing: f64, cell: f64) -> i64 {
    if field == Field::Paper1 {
        return 1;
    }
    ((BAND_SPACINGS * spacing / cell).ceil() as i64).clamp(1, 8)
}

fn positive(what: &'static str, value: f64, zero_ok: bool) -> Result<f64, ReconError> {
    if value.is_finite() && (value > 0.0 || (zero_ok && value == 0.0)) {
        Ok(value)
    } else {
        Err(ReconError::BadParameter { what, value })
    }
}
