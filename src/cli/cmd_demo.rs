//! `scanmesh demo`: the main job on the embedded sample: points sampled from
//! the Stanford dragon with noise, reconstructed into a mesh (normals on the
//! way; or, with `--method projection`, paper 2's triangulation of the
//! points themselves), then checked against the dragon's own triangles.

use super::stdout::outln;
use anyhow::Result;
use clap::Args;
use scanmesh::demo::dragon_scan;
use scanmesh::io::memory::MemoryReader;
use scanmesh::mesh::distance::{compare, Reference};
use scanmesh::mesh::{angle_report, self_intersections};
use scanmesh::mesh::{quality, Mesh, MeshFormat};
use scanmesh::normals::evaluate::{accuracy, normals_in_input_order};
use scanmesh::recon::implicit::reconstruct::{reconstruct_implicit, ImplicitParams};
use scanmesh::recon::projection::{reconstruct_projection, ProjectionParams};
use scanmesh::render::scene::{Scene, Style};
use scanmesh::store::{build::scratch_store_dir, build_store};
use std::path::PathBuf;
use std::time::Instant;

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

#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum DemoMethod {
    /// Signed distance + marching cubes (paper 1).
    Implicit,
    /// Local-projection triangulation of the points (paper 2).
    Projection,
}

pub fn run(a: DemoArgs) -> Result<()> {
    let s = a.common.settings()?;
    s.init_threads();
    let t0 = Instant::now();
    let (scan, dragon, spacing) = dragon_scan(a.n, 0.1, 1)?;
    outln!(
        "demo: {} points sampled from the embedded Stanford dragon ({} triangles), noise 0.1 x spacing ({:.3e})",
        scan.len(),
        dragon.faces.len(),
        spacing
    )?;
    let progress = super::progress::progress(s.quiet);
    // The dragon is a closed object: the watertight mode is its best mesh.
    let params = ImplicitParams {
        closed: true,
        ..ImplicitParams::default()
    };
    let dir = scratch_store_dir(&a.output);
    let mut reader = MemoryReader::new("embedded dragon sample", scan.points.clone(), None);
    let projection = ProjectionParams::default();
    let cost = match a.method {
        DemoMethod::Implicit => params.cost(),
        DemoMethod::Projection => projection.cost(),
    };
    s.check_floor(&cost)?;
    let opts = s.build_options(cost);
    let result = (|| -> Result<()> {
        let mut store = build_store(&mut reader, &dir, &opts, progress.as_ref())?;
        let (_, run_options) = s.plan_for(&store, cost)?;
        if a.method == DemoMethod::Projection {
            let r = reconstruct_projection(
                &mut store,
                &projection,
                &a.output,
                MeshFormat::PlyBinary,
                run_options,
                progress.as_ref(),
            )?;
            let secs = t0.elapsed().as_secs_f64();
            super::cmd_reconstruct_projection::print_summary(
                &r,
                store.tiles().len(),
                secs,
                &a.output,
            );
        } else {
            let r = reconstruct_implicit(
                &mut store,
                &params,
                &a.output,
                MeshFormat::PlyBinary,
                run_options,
                progress.as_ref(),
            )?;
            super::cmd_reconstruct::print_summary(
                &r,
                store.len(),
                store.tiles().len(),
                t0.elapsed().as_secs_f64(),
                &a.output,
            );
            let acc = accuracy(&normals_in_input_order(&store)?, &scan.normals);
            outln!(
                "demo: normals vs the dragon's faces: median angle {:.2} deg, {:.2} % oriented outward",
                acc.median_angle_deg,
                100.0 * acc.oriented_fraction
            )?;
        }
        let (v, t) = scanmesh::io::read_mesh_any(&a.output)?;
        let mesh = Mesh::new(v, t);
        outln!("{}", quality(&mesh))?;
        outln!("{}", angle_report(&mesh))?;
        outln!("{}", self_intersections(&mesh))?;
        picture(&mesh, &a.picture)?;
        let truth = Mesh::new(dragon.vertices.clone(), dragon.faces.clone());
        let d = compare(&mesh, Reference::Mesh(&truth));
        // One unit throughout: sp, the sample's mean nearest-neighbour
        // distance (`eval`'s own report uses the reference's, a different
        // number for the same distance).
        if let (Some(there), Some(back), Some(h)) = (
            d.mesh_to_reference.absolute,
            d.reference_to_mesh.absolute,
            d.hausdorff,
        ) {
            outln!(
                "demo: distance to the dragon in sp (the sample's mean nearest-neighbour distance, {spacing:.3e}): mean {:.3} sp (mesh to dragon {:.3}, dragon to mesh {:.3}), Hausdorff {:.2} sp",
                0.5 * (there.mean + back.mean) / spacing,
                there.mean / spacing,
                back.mean / spacing,
                h / spacing
            )?;
        }
        outln!(
            "demo: next, on a scan of your own: `scanmesh info scan.las`, then `scanmesh reconstruct scan.las -o mesh.ply` (open surface) or `--closed`, `scanmesh render --mesh mesh.ply -o mesh.png`; `scanmesh --help` lists every command"
        )?;
        Ok(())
    })();
    let _ = std::fs::remove_dir_all(&dir);
    result
}

/// Draws `mesh` seen from the front (the dragon's +z side, y up) into a
/// PNG at `path`.
fn picture(mesh: &Mesh, path: &std::path::Path) -> Result<()> {
    let scene = Scene {
        mesh: Some((mesh.vertices.clone(), mesh.triangles.clone())),
        ..Scene::default()
    };
    let style = Style {
        width: 1200,
        height: 900,
        forward: glam::DVec3::new(0.0, 0.0, -1.0),
        up: glam::DVec3::Y,
        point_radius: 1.0,
        line_width: 2.0,
    };
    let canvas = scene
        .draw(&style)
        .ok_or_else(|| anyhow::anyhow!("the demo mesh has nothing to draw"))?;
    canvas.write_png(path)?;
    outln!("demo: picture of the mesh -> {}", path.display())?;
    Ok(())
}
