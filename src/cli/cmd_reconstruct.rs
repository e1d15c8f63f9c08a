//! `scanmesh reconstruct`: a mesh from a point cloud (paper 1's implicit
//! method, seam-exact in tiles; paper 2's local projection, whose seams
//! are re-grown; or paper 4's Delaunay method, tiled and exact), streaming.

use super::args::{HoodArgs, ReconArgs};
use anyhow::{bail, Context, Result};
use clap::{Args, ValueEnum};
use scanmesh::io::mesh_format;
use scanmesh::io::place;
use scanmesh::recon::delaunay::reconstruct::{cost as delaunay_cost, reconstruct_delaunay};
use scanmesh::recon::implicit::reconstruct::{reconstruct_implicit, ImplicitParams};
use scanmesh::recon::projection::reconstruct_projection;
use scanmesh::store::{spacing::ensure_spacing, Kept, StageId};
use std::path::PathBuf;

super::command::command_args!(ReconstructArgs => run, run_dir |a| a.tile_stages(), plans |closed| ImplicitParams { closed, ..ImplicitParams::default() }.cost());
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
    #[command(flatten)]
    recon: ReconArgs,
    #[command(flatten)]
    hood: HoodArgs,
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

impl ReconstructArgs {
    /// The tile stages that can run as separate jobs (`--emit`).
    pub fn tile_stages(&self) -> Result<Vec<StageId>> {
        match self.method {
            Method::Implicit => Ok(vec![StageId::NORMALS, StageId::MARCHING_CUBES]),
            _ => bail!("--emit: only --method implicit runs its tiles as separate jobs yet"),
        }
    }
}

pub fn run(a: ReconstructArgs) -> Result<()> {
    let s = a.common.settings_in(&a.run)?;
    s.no_keep("a mesh")?;
    place::check_distinct(&a.input, &a.output)?;
    let format = mesh_format(&a.output, a.ascii)?;
    let (input, output, progress) = (&a.input, &a.output, s.progress());
    let places = (input.as_path(), output.as_path());
    match a.method {
        Method::Delaunay => {
            let params = a.recon.delaunay()?;
            let mut run = s.job().open(places, delaunay_cost(), Kept::Coordinates)?;
            let store = &mut run.ws.store;
            let r = reconstruct_delaunay(store, &params, output, format, run.opts, progress)
                .inspect_err(|e| s.log.with(|l| l.broken_promise(e.mesh())))
                .with_context(|| format!("reconstructing {}", input.display()))?;
            s.mesh_summary(&r.audit, s.closing(&r, output));
        }
        Method::Projection => {
            let params = a.recon.projection(&a.hood)?;
            let mut run = s.job().open(places, params.cost(), Kept::Coordinates)?;
            let store = &mut run.ws.store;
            let r = reconstruct_projection(store, &params, output, format, run.opts, progress)
                .inspect_err(|e| s.log.with(|l| l.broken_promise(e.mesh())))?;
            s.mesh_summary(&r.audit, s.closing(&r, output));
        }
        Method::Implicit => {
            let params = a.recon.implicit(&a.hood)?;
            let mut run = s.job().open(places, params.cost(), Kept::Nothing)?;
            let store = &mut run.ws.store;
            if params.cell.is_some() {
                // The run needs the spacing anyway; kept in the store's manifest.
                let cost = params.cost_with_spacing(ensure_spacing(store)?);
                s.lib.check_stage_space(store, output, &cost)?;
            }
            let r = reconstruct_implicit(store, &params, output, format, run.opts, progress)
                .inspect_err(|e| s.log.with(|l| l.broken_promise(e.mesh())))?;
            s.mesh_summary(&r.audit, s.closing(&r, output));
        }
    }
    Ok(())
}
