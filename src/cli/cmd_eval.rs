//! `scanmesh eval`: quality of a mesh, and its distance to a reference.

use super::stdout::outln;
use anyhow::Result;
use clap::Args;
use scanmesh::io::{open_reader, read_mesh_any, InvalidPolicy, PointChunk, ReadOptions, Selection};
use scanmesh::mesh::distance::{compare, Reference};
use scanmesh::mesh::{angle_report, quality, self_intersections, Mesh};
use serde_json::json;
use std::path::{Path, PathBuf};

super::command::command_args!(EvalArgs => run);
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
    /// With a point file as --reference: its points to compare with.
    #[command(flatten)]
    select: super::SelectArgs,
}

pub fn run(a: EvalArgs) -> Result<()> {
    let (vertices, triangles) = read_mesh_any(&a.mesh)?;
    let mesh = Mesh::new(vertices, triangles);
    mesh.validate()?;
    let q = quality(&mesh);
    let angles = angle_report(&mesh);
    let crossings = self_intersections(&mesh);
    let d = match &a.reference {
        Some(r) => Some(compare_to(&mesh, r, &a.select.selection())?),
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

fn compare_to(
    mesh: &Mesh,
    reference: &Path,
    select: &Selection,
) -> Result<scanmesh::mesh::distance::DistanceReport> {
    let (vertices, triangles) = match read_mesh_any(reference) {
        Ok(m) if select.is_all() => m,
        Ok(_) => anyhow::bail!(
            "{}: --classes and --returns select points of a point file; this reference is a mesh",
            reference.display()
        ),
        Err(_) => (read_points(reference, select)?, Vec::new()),
    };
    Ok(if triangles.is_empty() {
        compare(mesh, Reference::Points(&vertices))
    } else {
        compare(mesh, Reference::Mesh(&Mesh::new(vertices, triangles)))
    })
}

fn read_points(path: &Path, select: &Selection) -> Result<Vec<glam::DVec3>> {
    let read = ReadOptions {
        select: select.clone(),
        ..ReadOptions::from(InvalidPolicy::Reject)
    };
    let mut r = open_reader(path, read)?;
    let mut chunk = PointChunk::default();
    let mut pts = Vec::new();
    while r.read_chunk(&mut chunk, 1 << 16)? > 0 {
        pts.extend_from_slice(&chunk.xyz);
    }
    Ok(pts)
}
