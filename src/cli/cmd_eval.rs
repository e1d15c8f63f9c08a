//! `scanmesh eval`: quality of a mesh, and its distance to a reference.

use super::stdout::outln;
use anyhow::Result;
use clap::Args;
use scanmesh::io::{open_reader, read_mesh_any, InvalidPolicy, PointChunk};
use scanmesh::mesh::distance::{compare, Reference};
use scanmesh::mesh::{angle_report, quality, self_intersections, Mesh};
use serde_json::json;
use std::path::{Path, PathBuf};

#[derive(Args)]
pub struct EvalArgs {
    /// Mesh to evaluate (PLY or OBJ).
    mesh: PathBuf,
    /// Reference surface: a mesh, or a point file (distances both ways).
    #[arg(long)]
    reference: Option<PathBuf>,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
}

pub fn run(a: EvalArgs) -> Result<()> {
    let (vertices, triangles) = read_mesh_any(&a.mesh)?;
    let mesh = Mesh::new(vertices, triangles);
    mesh.validate()?;
    let q = quality(&mesh);
    let angles = angle_report(&mesh);
    let crossings = self_intersections(&mesh);
    let d = match &a.reference {
        Some(r) => Some(compare_to(&mesh, r)?),
        None => None,
    };
    if a.json {
        outln!(
            "{}",
            serde_json::to_string_pretty(&json!({
                "quality": q,
                "angles": angles,
                "self_intersections": crossings,
                "distance": d
            }))?
        )?;
    } else {
        outln!("{q}")?;
        outln!("{angles}")?;
        outln!("{crossings}")?;
        if let Some(d) = d {
            outln!("{d}")?;
        }
    }
    Ok(())
}

fn compare_to(mesh: &Mesh, reference: &Path) -> Result<scanmesh::mesh::distance::DistanceReport> {
    let (vertices, triangles) = match read_mesh_any(reference) {
        Ok(m) => m,
        Err(_) => (read_points(reference)?, Vec::new()),
    };
    Ok(if triangles.is_empty() {
        compare(mesh, Reference::Points(&vertices))
    } else {
        compare(mesh, Reference::Mesh(&Mesh::new(vertices, triangles)))
    })
}

fn read_points(path: &Path) -> Result<Vec<glam::DVec3>> {
    let mut r = open_reader(path, InvalidPolicy::Reject)?;
    let mut chunk = PointChunk::default();
    let mut pts = Vec::new();
    while r.read_chunk(&mut chunk, 1 << 16)? > 0 {
        pts.extend_from_slice(&chunk.xyz);
    }
    Ok(pts)
}
