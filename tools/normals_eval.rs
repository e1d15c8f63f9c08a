//! `normals-eval`: compares a point file's normals with the vertex normals of
//! a reference triangle mesh whose vertices are those points, in the same
//! order (e.g. `scanmesh normals dragon_vrip.ply.gz` against the dragon's own
//! triangles). Vertex normals are area-weighted face normals, right-hand
//! winding (outward for a consistently wound closed mesh).
//!
//! The reference may also be a point file with true normals (e.g. written by
//! `scangen --normals`), same points in the same order: then those normals
//! are the truth.

use anyhow::{bail, Result};
use clap::Parser;
use glam::DVec3;
use scanmesh::io::{open_reader, read_mesh_any, InvalidPolicy, PointChunk};
use scanmesh::normals::evaluate::{accuracy, accuracy_where, coincident};
use std::path::{Path, PathBuf};

#[derive(Parser)]
#[command(
    name = "normals-eval",
    about = "Normals of a point file against a reference mesh's vertex normals"
)]
struct Args {
    /// Point file with normals (as written by `scanmesh normals`).
    normals: PathBuf,
    /// Triangle mesh whose vertices are the same points in the same order, or
    /// a point file with true normals.
    #[arg(long)]
    reference: PathBuf,
    #[arg(long)]
    json: bool,
    /// Also print orientation disagreements binned by angle error.
    #[arg(long)]
    by_angle: bool,
}

/// Disagreements per 15-degree bin of unsigned angle error: flips of
/// accurate normals are orientation failures, flips of normals near 90
/// degrees off are undecidable.
fn print_by_angle(normals: &[DVec3], truth: &[DVec3]) {
    let mut bins = [(0usize, 0usize); 7];
    for (n, t) in normals.iter().zip(truth) {
        if *n == DVec3::ZERO || *t == DVec3::ZERO {
            continue;
        }
        let c = n.normalize().dot(t.normalize());
        let b = (c.abs().clamp(0.0, 1.0).acos().to_degrees() / 15.0) as usize;
        bins[b.min(6)].0 += 1;
        bins[b.min(6)].1 += usize::from(c < 0.0);
    }
    for (i, (all, wrong)) in bins.iter().enumerate().take(6) {
        println!(
            "  angle {:>2}-{:>2} deg: {all:>8} points, {wrong:>6} flipped",
            i * 15,
            i * 15 + 15
        );
    }
}

/// Area-weighted vertex normals of the reference mesh (or the reference
/// point file's own normals when it has no faces), and its positions.
fn truth_normals(path: &Path) -> Result<(Vec<DVec3>, Vec<DVec3>)> {
    let (vertices, faces) = read_mesh_any(path)?;
    if faces.is_empty() {
        return Ok((read_normals(path)?, vertices));
    }
    let mut truth = vec![DVec3::ZERO; vertices.len()];
    for f in &faces {
        let [p, q, r] = f.map(|i| vertices[i as usize]);
        // Cross product length is twice the area: area weighting for free.
        let n = (q - p).cross(r - p);
        for i in f {
            truth[*i as usize] += n;
        }
    }
    Ok((truth, vertices))
}

fn read_normals(path: &Path) -> Result<Vec<DVec3>> {
    let mut reader = open_reader(path, InvalidPolicy::Reject)?;
    let mut chunk = PointChunk::default();
    let mut normals = Vec::new();
    while reader.read_chunk(&mut chunk, 1 << 16)? > 0 {
        let Some(ns) = &chunk.normals else {
            bail!("{}: no normals", path.display());
        };
        normals.extend(ns.iter().map(|n| n.as_dvec3()));
    }
    Ok(normals)
}

fn main() -> Result<()> {
    let a = Args::parse();
    let (truth, positions) = truth_normals(&a.reference)?;
    let normals = read_normals(&a.normals)?;
    if normals.len() != truth.len() {
        bail!(
            "{} points but the reference has {}",
            normals.len(),
            truth.len()
        );
    }
    let acc = accuracy(&normals, &truth);
    let unique: Vec<bool> = coincident(&positions).iter().map(|c| !c).collect();
    let acc_unique = accuracy_where(&normals, &truth, &unique);
    let shared = unique.iter().filter(|u| !**u).count();
    if a.by_angle {
        print_by_angle(&normals, &truth);
    }
    if a.json {
        let report = serde_json::json!({ "all": acc, "unique_positions": acc_unique, "coincident_points": shared });
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        println!(
            "normals-eval: {} points compared, median angle {:.3} deg, 95th percentile {:.3} deg, oriented with the mesh {:.4} %",
            acc.compared,
            acc.median_angle_deg,
            acc.p95_angle_deg,
            100.0 * acc.oriented_fraction
        );
        println!(
            "  without the {shared} points at a position another reference point shares: median {:.3} deg, oriented {:.4} %",
            acc_unique.median_angle_deg,
            100.0 * acc_unique.oriented_fraction
        );
    }
    Ok(())
}
