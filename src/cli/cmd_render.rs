//! `scanmesh render`: a PNG of points, feature lines and a mesh, drawn by
//! the project's own rasteriser (orthographic, depth-buffered).

use super::stdout::outln;
use anyhow::{bail, Context, Result};
use clap::Args;
use glam::DVec3;
use scanmesh::features::lines::LineGraph;
use scanmesh::geom::parse_xyz;
use scanmesh::io::{open_reader, read_all_xyz, read_mesh_any};
use scanmesh::render::scene::{Scene, Style};
use std::path::PathBuf;

super::command::command_args!(RenderArgs => run);
#[derive(Args)]
pub struct RenderArgs {
    /// Output PNG.
    #[arg(short, long)]
    output: PathBuf,
    /// Points to draw (any point format), grey.
    #[arg(long)]
    points: Option<PathBuf>,
    /// Of --points: the points to draw.
    #[command(flatten)]
    select: super::SelectArgs,
    /// Feature lines (`scanmesh features` PLY): ridges red, valleys blue.
    #[arg(long)]
    lines: Option<PathBuf>,
    /// A triangle mesh (PLY or OBJ), shaded grey.
    #[arg(long)]
    mesh: Option<PathBuf>,
    /// Picture width in pixels.
    #[arg(long, default_value_t = 1200)]
    width: usize,
    /// Picture height in pixels.
    #[arg(long, default_value_t = 900)]
    height: usize,
    /// Viewing direction x,y,z (the camera looks along it).
    #[arg(long, default_value = "0,0,-1", value_parser = parse_xyz)]
    view: DVec3,
    /// Up direction x,y,z.
    #[arg(long, default_value = "0,1,0", value_parser = parse_xyz)]
    up: DVec3,
    /// Point splat radius in pixels.
    #[arg(long, default_value_t = 1.0)]
    point_size: f64,
    /// Line width in pixels.
    #[arg(long, default_value_t = 2.0)]
    line_width: f64,
}

pub fn run(a: RenderArgs) -> Result<()> {
    if a.points.is_none() && a.lines.is_none() && a.mesh.is_none() {
        bail!("nothing to draw: give --points, --lines or --mesh");
    }
    let mut scene = Scene::default();
    if let Some(p) = &a.points {
        let mut r = open_reader(p, a.select.read(true))
            .with_context(|| format!("reading {}", p.display()))?;
        scene.points = read_all_xyz(r.as_mut())?;
    }
    if let Some(l) = &a.lines {
        scene.lines = Some(LineGraph::read(l)?);
    }
    if let Some(m) = &a.mesh {
        scene.mesh = Some(read_mesh_any(m).with_context(|| format!("reading {}", m.display()))?);
    }
    let style = Style {
        width: a.width,
        height: a.height,
        forward: a.view,
        up: a.up,
        point_radius: a.point_size,
        line_width: a.line_width,
    };
    let Some(canvas) = scene.draw(&style) else {
        bail!("nothing finite to draw, or the view and up directions are parallel");
    };
    canvas.write_png(&a.output)?;
    outln!("render: {}x{} -> {}", a.width, a.height, a.output.display())?;
    Ok(())
}
