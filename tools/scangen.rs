//! `scangen`: seeded synthetic scans with known truth, streamed to any point
//! format (tests and benches generate in code; this is for the CLI benches
//! and for users who want a scan of a known surface).
//!
//! `scangen torus -n 1000000 -o torus.ply`
//! `scangen mesh --mesh dragon_vrip.ply.gz -n 10000000 --noise-spacing 0.1 -o dragon10m.ply`
//! `scangen ripples --wavelength 0.5 -o ripples.ply --truth ripples_lines.ply`

use anyhow::{bail, Context, Result};
use clap::Parser;
use glam::{DVec2, DVec3};
use scanmesh::geom::Aabb;
use scanmesh::io::{create_writer, format_from_name, read_mesh_any, PointChunk, WriterSpec};
use scanmesh::mesh::Mesh;
use scanmesh::synth::{mean_spacing_hint, stream, Shape, Terrain, TriMesh};
use std::path::PathBuf;

#[derive(Parser)]
#[command(
    name = "scangen",
    version,
    about = "Seeded synthetic laser scans with known truth"
)]
struct Args {
    /// sphere, torus, hole-plane, two-sheets, terrain, moebius, density-step, mesh,
    /// stepped-block, notched-box, wavy-sheet, cylinder, capsule, ripples.
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
    /// Crest height of the wavy-sheet or ripples shape (overrides the preset).
    #[arg(long)]
    amplitude: Option<f64>,
    /// Crest-to-crest distance of the wavy-sheet or ripples shape (overrides
    /// the preset).
    #[arg(long)]
    wavelength: Option<f64>,
    /// Also write the true normals.
    #[arg(long)]
    normals: bool,
    /// Output point file (.ply, .xyz, .csv, .las, .laz).
    #[arg(short, long)]
    output: PathBuf,
    /// Also write the shape's true feature lines (stepped-block,
    /// notched-box, wavy-sheet, ripples) to this PLY, in `scanmesh features`'
    /// format.
    #[arg(long)]
    truth: Option<PathBuf>,
    /// Also write the true surface as a triangle mesh (terrain: ground,
    /// walls and roofs on a 0.25-unit grid; the ground's chord error is
    /// under 1e-4 units), the reference `scanmesh eval` needs: a point-set
    /// reference sets a floor of its own spacing under every distance.
    #[arg(long)]
    truth_mesh: Option<PathBuf>,
}

fn main() -> Result<()> {
    let a = Args::parse();
    let mut shape = match (a.shape.as_str(), &a.mesh) {
        ("mesh", Some(path)) => {
            let (vertices, faces) = read_mesh_any(path)?;
            Shape::mesh(TriMesh { vertices, faces })
        }
        ("mesh", None) => bail!("the mesh shape needs --mesh <file>"),
        (name, _) => Shape::preset(name).with_context(|| format!("unknown shape {name}"))?,
    };
    override_waves(&mut shape, a.amplitude, a.wavelength)?;
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
        let format = scanmesh::io::mesh_format(path, false)?;
        scanmesh::features::lines::LineGraph::from_segments(&lines).write(
            path,
            glam::DVec3::ZERO,
            format,
        )?;
    }
    if let Some(path) = &a.truth_mesh {
        let Shape::Terrain(t) = &shape else {
            bail!(
                "{}: --truth-mesh is written for the terrain only",
                shape.name()
            );
        };
        let mesh = terrain_mesh(t, 0.25);
        scanmesh::mesh::write_mesh(path, &mesh, scanmesh::mesh::MeshFormat::PlyBinary)?;
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

/// `--amplitude` and `--wavelength` applied to a wavy sheet or ripples; an
/// error for any other shape. The sampler validates the values.
fn override_waves(
    shape: &mut Shape,
    amplitude: Option<f64>,
    wavelength: Option<f64>,
) -> Result<()> {
    if amplitude.is_none() && wavelength.is_none() {
        return Ok(());
    }
    let (a, w) = match shape {
        Shape::WavySheet(s) => (&mut s.amplitude, &mut s.wavelength),
        Shape::Ripples {
            amplitude,
            wavelength,
            ..
        } => (amplitude, wavelength),
        other => bail!(
            "{}: --amplitude and --wavelength are for wavy-sheet and ripples only",
            other.name()
        ),
    };
    *a = amplitude.unwrap_or(*a);
    *w = wavelength.unwrap_or(*w);
    Ok(())
}

/// The terrain's true surface: the ground on a grid of `step` (cells inside
/// a footprint left out: footprints lie on the grid), each building's walls
/// from the ground to the roof in strips of `step`, and its roof.
fn terrain_mesh(t: &Terrain, step: f64) -> Mesh {
    let half = 0.5 * t.side;
    let n = (t.side / step).round() as usize;
    let at = |i: usize| -half + i as f64 * step;
    let mut m = Mesh::default();
    for j in 0..=n {
        for i in 0..=n {
            m.vertices
                .push(DVec3::new(at(i), at(j), t.height(at(i), at(j)).0));
        }
    }
    let node = |i: usize, j: usize| (j * (n + 1) + i) as u32;
    for j in 0..n {
        for i in 0..n {
            if t.in_footprint(at(i) + 0.5 * step, at(j) + 0.5 * step) {
                continue;
            }
            let (a, b, c, d) = (
                node(i, j),
                node(i + 1, j),
                node(i + 1, j + 1),
                node(i, j + 1),
            );
            m.triangles.extend([[a, b, c], [a, c, d]]);
        }
    }
    for b in &t.buildings {
        let corners = [
            DVec2::new(b.min.x, b.min.y),
            DVec2::new(b.max.x, b.min.y),
            DVec2::new(b.max.x, b.max.y),
            DVec2::new(b.min.x, b.max.y),
        ];
        for k in 0..4 {
            let (p, q) = (corners[k], corners[(k + 1) % 4]);
            let steps = ((q - p).length() / step).ceil().max(1.0) as usize;
            let first = m.vertices.len() as u32;
            for s in 0..=steps {
                let xy = p + (q - p) * (s as f64 / steps as f64);
                m.vertices
                    .push(DVec3::new(xy.x, xy.y, t.height(xy.x, xy.y).0));
                m.vertices.push(DVec3::new(xy.x, xy.y, b.roof));
            }
            for s in 0..steps as u32 {
                let (lo, hi, lo2, hi2) = (
                    first + 2 * s,
                    first + 2 * s + 1,
                    first + 2 * s + 2,
                    first + 2 * s + 3,
                );
                m.triangles.extend([[lo, lo2, hi2], [lo, hi2, hi]]);
            }
        }
        let first = m.vertices.len() as u32;
        m.vertices
            .extend(corners.iter().map(|c| DVec3::new(c.x, c.y, b.roof)));
        m.triangles
            .extend([[first, first + 1, first + 2], [first, first + 2, first + 3]]);
    }
    without_unused_vertices(m)
}

/// `m` without the vertices no triangle uses (`eval` measures from every
/// vertex of a reference, so ground nodes inside a footprint must go).
fn without_unused_vertices(m: Mesh) -> Mesh {
    let mut map = vec![u32::MAX; m.vertices.len()];
    let mut out = Mesh::default();
    for t in &m.triangles {
        out.triangles.push(t.map(|v| {
            if map[v as usize] == u32::MAX {
                map[v as usize] = out.vertices.len() as u32;
                out.vertices.push(m.vertices[v as usize]);
            }
            map[v as usize]
        }));
    }
    out
}
