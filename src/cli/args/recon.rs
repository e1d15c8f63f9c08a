//! The reconstruction methods' flags (`reconstruct`) and their mapping
//! onto each method's parameters; an error names the flag to change.

use super::HoodArgs;
use anyhow::{bail, Result};
use clap::Args;
use scanmesh::recon::delaunay::reconstruct::DelaunayParams;
use scanmesh::recon::implicit::field::Field;
use scanmesh::recon::implicit::reconstruct::{ImplicitParams, ReconError};
use scanmesh::recon::projection::ProjectionParams;

/// The flags of the three methods, in the order `--help` lists them.
#[derive(Args)]
pub struct ReconArgs {
    /// Marching-cubes cell edge (default: 2.2 x the mean spacing, 3 x with --closed; rho + delta, as paper 1 advises, with --plane sample).
    #[arg(long)]
    cell: Option<f64>,
    /// Noise bound delta (default: estimated from the tangent-plane fits).
    #[arg(long)]
    noise: Option<f64>,
    /// The surface is closed: watertight, manifold and outward, by
    /// construction (paper 1 section 4.1). Away from the data each lattice
    /// corner takes the sign of the samples' winding number, so where the
    /// scan has a hole (an unscanned base) the surface closes across it
    /// the way the surface around it runs; an open scan (a terrain) closes
    /// into a slab. Pieces smaller than --min-piece are dropped.
    #[arg(long)]
    closed: bool,
    /// The signed distance (--method implicit): `mls` (default) averages
    /// the tangent planes of the 16 nearest samples over about two local
    /// spacings and moves each vertex onto that surface; `sample` is
    /// paper 1's plane through the nearest sample (keeps sharp edges
    /// sharpest, follows the noise), vertices linearly interpolated.
    #[arg(long, value_enum, default_value_t = Field::Mls)]
    plane: Field,
    /// Flat blocks (--method implicit): a block of 4 x 4 x 4 cells whose
    /// triangles form one flat disk is triangulated from its rim alone if
    /// no vertex left out lies farther than this, in mean spacings
    /// (default 0: all kept). 0.1 halves flat ground, walls and roofs; a
    /// surface curved everywhere loses some accuracy (README).
    #[arg(long, value_name = "SPACINGS")]
    flat_tolerance: Option<f64>,
    /// Sampling-hole radius of paper 4 (--method delaunay), absolute:
    /// triangles with a larger circumradius are boundaries. Default: 5 x
    /// the largest spacing of the triangle's corners, a corner's spacing
    /// being its nearest-neighbour distance but at most 4 x its
    /// neighbour's (from the local sampling, not the paper's share of the
    /// bounding sphere; an outlier is not sparse sampling).
    #[arg(long, value_name = "DELTA")]
    hole: Option<f64>,
    /// Drop connected pieces with fewer triangles than this share of the
    /// largest piece's (default 0.01 with --closed, else 0: keep all).
    #[arg(long, value_name = "SHARE")]
    min_piece: Option<f64>,
    /// Neighbours per point for the normals (per query when topological);
    /// for --method projection, each vertex's neighbourhood (paper 2: 6..15).
    #[arg(long, default_value_t = 12)]
    k: usize,
    /// --method projection: leave out a point closer than this many local
    /// spacings to a point of smaller input id (0 keeps every point).
    #[arg(long, default_value_t = ProjectionParams::default().thin)]
    thin: f64,
    /// --method projection: longest edge, in local spacings.
    #[arg(long, default_value_t = ProjectionParams::default().max_edge)]
    max_edge: f64,
}

impl ReconArgs {
    /// Paper 4's parameters (`--hole`).
    pub fn delaunay(&self) -> Result<DelaunayParams> {
        let params = DelaunayParams { hole: self.hole };
        // Checked again by the library; here before any input is read.
        if let Err(e) = params.validate() {
            bail!("--hole: {e}");
        }
        Ok(params)
    }

    /// Paper 2's parameters, the vertices' neighbourhood from `hood`.
    pub fn projection(&self, hood: &HoodArgs) -> Result<ProjectionParams> {
        let params = ProjectionParams {
            k: self.k,
            neighbourhood: hood.hood(),
            thin: self.thin,
            max_edge: self.max_edge,
            ..ProjectionParams::default()
        };
        // Checked again by the library; here before any input is read.
        params.validate().map_err(|e| {
            anyhow::anyhow!("--{} {}: {}", e.name.replace('_', "-"), e.value, e.why)
        })?;
        Ok(params)
    }

    /// Paper 1's parameters, the normals' neighbourhood from `hood`.
    pub fn implicit(&self, hood: &HoodArgs) -> Result<ImplicitParams> {
        let mut params = ImplicitParams {
            cell: self.cell,
            noise: self.noise,
            closed: self.closed,
            min_piece: self.min_piece,
            flat_tolerance: self.flat_tolerance,
            field: self.plane,
            ..ImplicitParams::default()
        };
        params.normals.k = self.k;
        params.normals.neighbourhood = hood.hood();
        // Checked again by the library; here before any input is read.
        params.validate().map_err(|e| match e {
            ReconError::BadShare(v) => anyhow::anyhow!("--min-piece {v}: {e}"),
            ReconError::BadFlatTolerance(v) => anyhow::anyhow!("--flat-tolerance {v}: {e}"),
            ReconError::BadParameter { what, value } => anyhow::anyhow!("--{what} {value}: {e}"),
            ReconError::Normals(_) => anyhow::anyhow!("--k {}: {e}", self.k),
            e => e.into(),
        })?;
        Ok(params)
    }
}
