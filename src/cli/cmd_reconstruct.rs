//! `scanmesh reconstruct`: a mesh from a point cloud (paper 1's implicit
//! method, seam-exact in tiles; or paper 2's local projection, whose seams
//! are re-grown), streaming.

use anyhow::{bail, Result};
use clap::{Args, ValueEnum};
use scanmesh::mesh::MeshFormat;
use scanmesh::recon::implicit::field::Field;
use scanmesh::recon::implicit::reconstruct::{
    reconstruct_implicit, ImplicitParams, ImplicitReport, ReconError,
};
use scanmesh::recon::projection::ProjectionParams;
use scanmesh::store::StageId;
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(Args)]
pub struct ReconstructArgs {
    /// Input point file or store directory.
    pub input: PathBuf,
    /// Output mesh (.ply binary by default, .obj).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Reconstruction method.
    #[arg(long, value_enum, default_value_t = Method::Implicit)]
    method: Method,
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
    #[arg(long, value_enum, default_value_t = Plane::Mls)]
    plane: Plane,
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
    #[command(flatten)]
    hood: super::cmd_normals::HoodArgs,
    /// Write PLY as ASCII instead of binary.
    #[arg(long)]
    ascii: bool,
    #[command(flatten)]
    pub common: super::CommonArgs,
    #[command(flatten)]
    pub run: super::RunDirArgs,
}

#[derive(Clone, Copy, ValueEnum)]
enum Method {
    /// Signed distance to tangent planes + marching cubes (paper 1).
    Implicit,
    /// Greedy local-projection Delaunay triangulation (paper 2): the
    /// input points are the vertices.
    Projection,
    /// 3-D Delaunay triangulation and local flatness (paper 4): the
    /// input points are the vertices; open, multi-sheet and non-orientable
    /// surfaces.
    Delaunay,
}

#[derive(Clone, Copy, ValueEnum)]
enum Plane {
    /// Moving least squares over the local spacing (issue 19).
    Mls,
    /// Paper 1's definition: the nearest sample's tangent plane.
    Sample,
}

pub fn mesh_format(path: &Path, ascii: bool) -> Result<MeshFormat> {
    Ok(scanmesh::io::mesh_format(path, ascii)?)
}

impl ReconstructArgs {
    /// The tile stages that can run as separate jobs (`--emit`).
    pub fn tile_stages(&self) -> Result<Vec<StageId>> {
        match self.method {
            Method::Implicit => Ok(vec![StageId::Normals, StageId::MarchingCubes]),
            _ => bail!("--emit: only --method implicit runs its tiles as separate jobs yet"),
        }
    }
}

pub fn run(a: ReconstructArgs) -> Result<()> {
    let s = a.common.settings_in(&a.run)?;
    s.no_keep("a mesh")?;
    s.init_threads();
    super::check_distinct(&a.input, &a.output)?;
    let format = mesh_format(&a.output, a.ascii)?;
    if let Method::Delaunay = a.method {
        return super::cmd_reconstruct_delaunay::run(&s, &a.input, &a.output, format, a.hole);
    }
    if let Method::Projection = a.method {
        let params = ProjectionParams {
            k: a.k,
            neighbourhood: a.hood.hood(),
            thin: a.thin,
            max_edge: a.max_edge,
            ..ProjectionParams::default()
        };
        return super::cmd_reconstruct_projection::run(&s, &a.input, &a.output, format, &params);
    }
    let mut params = ImplicitParams {
        cell: a.cell,
        noise: a.noise,
        closed: a.closed,
        min_piece: a.min_piece,
        field: match a.plane {
            Plane::Mls => Field::Mls,
            Plane::Sample => Field::Paper1,
        },
        ..ImplicitParams::default()
    };
    params.normals.k = a.k;
    params.normals.neighbourhood = a.hood.hood();
    // Checked again by the library; here before any input is read.
    params.validate().map_err(|e| match e {
        ReconError::BadShare(v) => anyhow::anyhow!("--min-piece {v}: {e}"),
        ReconError::BadParameter { what, value } => anyhow::anyhow!("--{what} {value}: {e}"),
        ReconError::Normals(_) => anyhow::anyhow!("--k {}: {e}", a.k),
        e => e.into(),
    })?;
    let progress = super::progress::progress(s.quiet);
    let t0 = Instant::now();
    let mut run = s.open_input(&a.input, &a.output, params.cost(), progress.as_ref())?;
    if params.cell.is_some() {
        // The run needs the spacing anyway; kept in the store's manifest.
        let spacing = scanmesh::store::spacing::ensure_spacing(&mut run.ws.store)?;
        s.check_stage_space(&run.ws.store, &a.output, &params.cost_with_spacing(spacing))?;
    }
    let r = reconstruct_implicit(
        &mut run.ws.store,
        &params,
        &a.output,
        format,
        run.opts,
        progress.as_ref(),
    )
    .inspect_err(|e| super::report::broken_promise(e.mesh()))?;
    print_summary(
        &r,
        run.ws.store.len(),
        run.ws.store.tiles().len(),
        t0.elapsed().as_secs_f64(),
        &a.output,
    );
    Ok(())
}

pub fn print_summary(r: &ImplicitReport, points: u64, tiles: usize, secs: f64, out: &Path) {
    super::report::mesh_audit(&r.audit);
    super::report::summary(format!(
        "reconstruct: {} points, {} tiles, rho {:.4e} ({} outliers left out), delta {:.4e}, cell {:.4e}, {} cubes -> {} vertices, {} triangles{}, {:.2} s, peak {} -> {}; checked: {}",
        points,
        tiles,
        r.rho,
        r.rho_outliers,
        r.delta,
        r.cell,
        r.cubes,
        r.vertices,
        r.triangles,
        changes_summary(r),
        secs,
        super::peak(),
        out.display(),
        r.audit
    ));
}

/// " (P small pieces dropped, A % of the surface closed away from the
/// data)", the parts that apply.
fn changes_summary(r: &ImplicitReport) -> String {
    let p = r.pieces;
    let mut parts = Vec::new();
    if r.away_triangles > 0 {
        let drawn = r.triangles + p.triangles_dropped;
        parts.push(format!(
            "{:.2} % of the surface closed away from the data",
            100.0 * r.away_triangles as f64 / drawn.max(1) as f64
        ));
    }
    if p.pieces_dropped > 0 {
        parts.push(format!(
            "{} small pieces dropped ({} triangles)",
            p.pieces_dropped, p.triangles_dropped
        ));
    }
    if parts.is_empty() {
        String::new()
    } else {
        format!(" ({})", parts.join(", "))
    }
}
