//! `scanmesh reconstruct`: a mesh from a point cloud (paper 1's implicit
//! method, seam-exact in tiles; or paper 2's local projection, whose seams
//! are re-grown), streaming.

use super::args::{HoodArgs, ReconArgs};
use anyhow::{bail, Result};
use clap::{Args, ValueEnum};
use scanmesh::io::mesh_format;
use scanmesh::recon::implicit::reconstruct::reconstruct_implicit;
use scanmesh::store::StageId;
use std::path::PathBuf;
use std::time::Instant;

super::command::command_args!(ReconstructArgs => run, run_dir |a| a.tile_stages());
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
    let (input, output) = (&a.input, &a.output);
    match a.method {
        Method::Delaunay => {
            let params = a.recon.delaunay()?;
            return super::cmd_reconstruct_delaunay::run(&s, input, output, format, &params);
        }
        Method::Projection => {
            let params = a.recon.projection(&a.hood)?;
            return super::cmd_reconstruct_projection::run(&s, input, output, format, &params);
        }
        Method::Implicit => {}
    }
    let params = a.recon.implicit(&a.hood)?;
    let progress = s.progress();
    let t0 = Instant::now();
    let mut run = s.open_input(input, output, params.cost(), progress)?;
    if params.cell.is_some() {
        // The run needs the spacing anyway; kept in the store's manifest.
        let spacing = scanmesh::store::spacing::ensure_spacing(&mut run.ws.store)?;
        s.lib
            .check_stage_space(&run.ws.store, output, &params.cost_with_spacing(spacing))?;
    }
    let r = reconstruct_implicit(
        &mut run.ws.store,
        &params,
        output,
        format,
        run.opts,
        progress,
    )
    .inspect_err(|e| s.log.with(|l| l.broken_promise(e.mesh())))?;
    s.mesh_summary(&r.audit, super::closing(&r, t0, output));
    Ok(())
}
