//! `scanmesh demo`: the main job on the embedded sample: points sampled from
//! the Stanford dragon with noise, reconstructed into a mesh (normals on the
//! way; or, with `--method projection`, paper 2's triangulation of the
//! points themselves), then checked against the dragon's own triangles.

use super::stdout::outln;
use anyhow::Result;
use clap::Args;
use scanmesh::demo::{
    normals_line, picture, DemoCheck, DemoMesh, DemoMethod, DemoSample, NEXT_STEPS,
};
use std::path::PathBuf;

super::command::command_args!(DemoArgs => run, common);
#[derive(Args)]
pub struct DemoArgs {
    /// Where to write the mesh.
    #[arg(short, long, default_value = "scanmesh-demo.ply")]
    output: PathBuf,
    /// Where to write a picture of the mesh (PNG, the project's own
    /// renderer).
    #[arg(long, default_value = "scanmesh-demo.png")]
    picture: PathBuf,
    /// Points to sample from the embedded dragon.
    #[arg(short, default_value_t = 200_000)]
    n: usize,
    /// Reconstruction method.
    #[arg(long, value_enum, default_value_t = DemoMethod::Implicit)]
    method: DemoMethod,
    #[command(flatten)]
    pub common: super::CommonArgs,
}

pub fn run(a: DemoArgs) -> Result<()> {
    let s = a.common.settings()?;
    let sample = DemoSample::new(a.n)?;
    outln!("{sample}")?;
    let progress = s.progress();
    s.lib.check_floor(&a.method.cost())?;
    let out = &a.output;
    match a.method.reconstruct(&sample, &s.lib, out, progress)? {
        DemoMesh::Projection(r) => s.mesh_summary(&r.audit, s.closing(&r, out)),
        DemoMesh::Implicit(r, normals) => {
            s.mesh_summary(&r.audit, s.closing(&r, out));
            outln!("{}", normals_line(&normals))?;
        }
    }
    let check = DemoCheck::of(out, &sample)?;
    for line in &check.checks {
        outln!("{line}")?;
    }
    outln!("{}", picture(&check.mesh, &a.picture)?)?;
    if let Some(line) = check.distance_line() {
        outln!("{line}")?;
    }
    outln!("{NEXT_STEPS}")?;
    Ok(())
}
