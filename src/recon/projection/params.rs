//! Parameters of the local-projection triangulation, with defaults that need
//! no tuning: every length is relative to the *local* spacing of the points
//! involved, so one setting serves a uniform scan, a 20:1 density step and
//! terrain.

use crate::memory::plan::KernelCost;
use crate::normals::{NormalHood, NormalParams};

/// Parameters of the local-projection triangulation (paper 2); lengths in local spacings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProjectionParams {
    /// Neighbourhood of each vertex: the k nearest (paper 2 section 2.4,
    /// k in 6..15) or paper 3's topological neighbours.
    pub k: usize,
    /// Which neighbourhood `k` counts (the k nearest, or paper 3's topological neighbours).
    pub neighbourhood: NormalHood,
    /// A point closer than this many local spacings to a point of smaller
    /// input id is left out (0 keeps every point); see `thin.rs`.
    pub thin: f64,
    /// Longest edge, in local spacings (the larger of its ends').
    pub max_edge: f64,
    /// Neighbours higher over the tangent plane than this angle, seen from
    /// the vertex, are not connected (another sheet, or a fold).
    pub max_elevation_deg: f64,
    /// Largest corner angle of a triangle.
    pub max_angle_deg: f64,
}

/// Default k: the middle of the paper's range. Measured on the 1M noisy
/// dragon (see the module docs of `recon::projection`).
pub const DEFAULT_K: usize = 12;

/// Default thinning, in local spacings (`thin.rs`). Measured on the 1M
/// noisy dragon, the same store of 6 tiles: 0.6 left 1.24 % of the
/// triangles under 10 degrees, 0.7 left 0.96 %, with the same 62 boundary
/// loops, 0 non-manifold, inconsistent or self-intersecting, and the same
/// mean distances to the dragon mesh (0.046 / 0.052 of the reference's
/// spacing, mesh to dragon / dragon to mesh).
pub const DEFAULT_THIN: f64 = 0.7;

impl Default for ProjectionParams {
    fn default() -> Self {
        ProjectionParams {
            k: DEFAULT_K,
            neighbourhood: NormalHood::Knn,
            thin: DEFAULT_THIN,
            max_edge: 8.0,
            max_elevation_deg: 45.0,
            max_angle_deg: 170.0,
        }
    }
}

/// A parameter outside its range.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{name} = {value}: {why}")]
pub struct BadParameter {
    /// The field of [`ProjectionParams`] that is out of range.
    pub name: &'static str,
    /// The value it was given.
    pub value: f64,
    /// The range it must lie in.
    pub why: &'static str,
}

impl ProjectionParams {
    /// Checks every field's range.
    pub fn validate(&self) -> Result<(), BadParameter> {
        let bad = |name, value, why| Err(BadParameter { name, value, why });
        if !(3..=64).contains(&self.k) {
            return bad("k", self.k as f64, "must be between 3 and 64");
        }
        if !(0.0..1.0).contains(&self.thin) {
            return bad("thin", self.thin, "must be in [0, 1) local spacings");
        }
        if !(self.max_edge.is_finite() && self.max_edge >= 1.0) {
            return bad(
                "max_edge",
                self.max_edge,
                "must be at least 1 local spacing",
            );
        }
        if !(0.0 < self.max_elevation_deg && self.max_elevation_deg < 90.0) {
            return bad(
                "max_elevation_deg",
                self.max_elevation_deg,
                "must be in (0, 90) degrees",
            );
        }
        if !(60.0 < self.max_angle_deg && self.max_angle_deg < 180.0) {
            return bad(
                "max_angle_deg",
                self.max_angle_deg,
                "must be in (60, 180) degrees",
            );
        }
        Ok(())
    }

    /// The neighbourhood as the normals module's parameters (same index).
    pub fn hood(&self) -> NormalParams {
        NormalParams {
            k: self.k,
            neighbourhood: self.neighbourhood,
            ..NormalParams::default()
        }
    }

    /// What a run costs, for the memory plan (measured, see
    /// `BYTES_PER_POINT_BASE`): the kernel's bytes per loaded point, one
    /// tile at a time (its lattice jobs keep every thread busy), and the
    /// lattice's margin in spacings, which sets how many points a tile
    /// loads. Measured peaks (jemalloc, one tile in flight): 1M points in
    /// one tile at the default 1 GiB, 303 MiB; at `--mem 256MiB`, 4 tiles,
    /// 175 MiB; 3M at 512 MiB, 4 tiles, 380 MiB; 10M at 512 MiB, 16 tiles,
    /// 361 MiB; 10M at 256 MiB, 32 tiles, 261 MiB (the flat margin factor
    /// planned those: the margin model makes the small budgets' tiles
    /// smaller, see `MARGIN_SPACINGS`).
    pub fn cost(&self) -> KernelCost {
        let k = self.k as u64;
        let per_k = match self.neighbourhood {
            NormalHood::Knn => BYTES_PER_POINT_PER_K,
            NormalHood::Topological { .. } => 2 * BYTES_PER_POINT_PER_K,
        };
        KernelCost {
            bytes_per_point: BYTES_PER_POINT_BASE + per_k * k,
            global_per_point: 0,
            contracts_boundaries: false,
            // The pieces the stitcher settles at the end: a few per
            // lattice job, a fraction of a byte per point.
            resident_per_point: 0.0,
            window_bytes_per_point: 0,
            // Beside the store: the triangle spool (16 B, two per point).
            scratch_per_point: 2 * 16,
            export_scratch_per_point: 2 * 16,
            checkpoint_per_point: 0,
            external_scratch_saving: 0,
            export_frees_positions: false,
            // Vertices (3 f64) and faces (13 B, two per point).
            output_per_point: 24 + 2 * 13,
            // The face spool and the audit beside the output, two triangles
            // per point.
            beside_output_per_point: (2.0 * crate::mesh::SCRATCH_BESIDE_OUTPUT_PER_TRIANGLE) as u64,
            parallel_in_tile: true,
            margin_spacings: MARGIN_SPACINGS,
            resident_bytes: 0,
        }
    }
}

/// The tile margin in mean spacings: `reconstruct.rs` asks for a lattice
/// cell less the band, plus spill, view and two list reaches, times 1.05:
/// about 112 lattice units, and a unit (0.8 x extent / sqrt(n)) is 1.2
/// spacings on the dragon. Below that, at 10M points in 256 MiB (32 tiles
/// of 312k points) the peak was 261 MiB: tiles that small load more than
/// twice their core.
pub const MARGIN_SPACINGS: f64 = 140.0;

/// Kernel bytes per loaded point beside the neighbour lists. Measured with
/// `peak-rss` on the 1M dragon as one tile, one thread (the tile's points,
/// kNN index, planes, spacings, states, directed edges, fixed triangles):
/// 326 MiB at k = 12, 372 MiB at k = 24, so ~4 B per neighbour and ~270 B
/// beside them once the binary and the mapped store are taken off; a
/// tenth more for denser or noisier tiles.
pub const BYTES_PER_POINT_BASE: u64 = 300;
/// Kernel bytes per loaded point per neighbour (the list's id and the
/// search's scratch).
pub const BYTES_PER_POINT_PER_K: u64 = 6;
