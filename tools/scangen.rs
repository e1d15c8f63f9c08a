//! `scangen`: seeded synthetic scans with known truth, streamed to any point
//! format (tests and benches generate in code; this is for the CLI benches
//! and for users who want a scan of a known surface).
//!
//! `scangen torus -n 1000000 -o torus.ply`
//! `scangen mesh --mesh dragon_vrip.ply.gz -n 10000000 --noise-spacing 0.1 -o dragon10m.ply`

use anyhow::{bail, Context, Result};
use clap::Parser;
use scanmesh::geom::Aabb;
use scanmesh::io::{create_writer, format_from_name, read_mesh_any, PointChunk, WriterSpec};
use scanmesh::synth::{mean_spacing_hint, stream, Shape, TriMesh};
use std::path::PathBuf;

#[derive(Parser)]
#[command(
    name = "scangen",
    version,
    about = "Seeded synthetic laser scans with known truth"
)]
struct Args {
    /// sphere, torus, hole-plane, two-sheets, terrain, moebius, density-step, mesh,
    /// stepped-block, notched-box, wavy-sheet.
    shape: String,
    /// Number of points.
    #[arg(short, default_value_t = 100_000)]
    n: usize,
    /// Gaussian noise sigma, absolute.
    #[arg(long, default_value_t = 0.0)]
    noise: f64,
    /// Gaussian noise sigma as a fraction of the expected mean spacing
    /// (overrides --noise).
    #[arg(long)]
    noise_spacing: Option<f64>,
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Triangle mesh to sample (PLY or OBJ, .gz ok) for the `mesh` shape.
    #[arg(long)]
    mesh: Option<PathBuf>,
    /// Also write the true normals.
    #[arg(long)]
    normals: bool,
    /// Output point file (.ply, .xyz, .csv, .las, .laz).
    #[arg(short, long)]
    output: PathBuf,
    /// Also write the shape's true feature lines (stepped-block,
    /// notched-box, wavy-sheet) to this PLY, in `scanmesh features`' format.
    #[arg(long)]
    truth: Option<PathBuf>,
}

fn main() -> Result<()> {
    let a = Args::parse();
    let shape = match (a.shape.as_str(), &a.mesh) {
        ("mesh", Some(path)) => {
            let (vertices, faces) = read_mesh_any(path)?;
            Shape::mesh(TriMesh { vertices, faces })
        }
        ("mesh", None) => bail!("the mesh shape needs --mesh <file>"),
        (name, _) => Shape::preset(name).with_context(|| format!("unknown shape {name}"))?,
    };
    let noise = match a.noise_spacing {
        Some(f) => f * mean_spacing_hint(&shape, a.n)?,
        None => a.noise,
    };
    let Some((format, _)) = format_from_name(&a.output) else {
        bail!("{}: unknown output format", a.output.display());
    };
    // LAS needs bounds up front: a first noise-free pass bounds the surface,
    // padded by 6 sigma of noise.
    let bounds = if matches!(
        format,
        scanmesh::io::Format::Las | scanmesh::io::Format::Laz
    ) {
        let mut b = Aabb::EMPTY;
        for s in stream(&shape, a.n, 0.0, a.seed)? {
            b.add(s.p);
        }
        Some(b.expanded(6.0 * noise + 1e-9))
    } else {
        None
    };
    let spec = WriterSpec {
        format,
        with_normals: a.normals,
        with_flags: false,
        bounds,
        ..WriterSpec::new(format)
    };
    let mut writer = create_writer(&a.output, &spec)?;
    let mut samples = stream(&shape, a.n, noise, a.seed)?;
    let mut chunk = PointChunk::default();
    while samples.fill_chunk(&mut chunk, 1 << 16) > 0 {
        if !a.normals {
            chunk.normals = None;
        }
        writer.write_chunk(&chunk, None)?;
    }
    let n = writer.finish()?;
    if let Some(path) = &a.truth {
        let Some(lines) = shape.feature_lines() else {
            bail!("{}: has no known feature lines", shape.name());
        };
        scanmesh::features::lines::LineGraph::from_segments(&lines).write(
            path,
            glam::DVec3::ZERO,
            false,
        )?;
    }
    eprintln!(
        "scangen: {} {} points, noise {:.3e} -> {}",
        n,
        shape.name(),
        noise,
        a.output.display()
    );
    Ok(())
}
