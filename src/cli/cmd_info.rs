//! `scanmesh info`: what a file or a store holds.

use anyhow::Result;
use clap::Args;
use scanmesh::io::inspect::inspect;
use scanmesh::io::InvalidPolicy;
use scanmesh::store::{is_store, PointStore};
use serde_json::json;
use std::path::PathBuf;

#[derive(Args)]
pub struct InfoArgs {
    /// A point file (PLY, XYZ/CSV, LAS/LAZ, optionally .gz) or a store directory.
    input: PathBuf,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
    /// No progress bar.
    #[arg(long, short)]
    quiet: bool,
}

pub fn run(a: InfoArgs) -> Result<()> {
    let report = if is_store(&a.input) {
        store_report(&a.input)?
    } else {
        let progress = super::progress::progress(a.quiet);
        let r = inspect(&a.input, InvalidPolicy::Reject, progress.as_ref())?;
        json!({
            "path": a.input.display().to_string(),
            "format": format!("{:?}", r.info.format),
            "gzip": r.info.gzip,
            "declared_points": r.info.declared_count,
            "points": r.count,
            "has_normals": r.info.has_normals,
            "bounds_min": r.bounds.min.to_array(),
            "bounds_max": r.bounds.max.to_array(),
            "spacing_estimate": r.spacing,
            "las_scale": r.info.las_transform.map(|t| t.scale.to_array()),
            "las_offset": r.info.las_transform.map(|t| t.offset.to_array()),
        })
    };
    if a.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print_text(&report);
    }
    Ok(())
}

fn store_report(dir: &std::path::Path) -> Result<serde_json::Value> {
    let store = PointStore::open(dir)?;
    let m = &store.manifest;
    let largest = m.tiles.iter().map(|t| t.count).max().unwrap_or(0);
    Ok(json!({
        "path": dir.display().to_string(),
        "format": "store",
        "points": m.count,
        "tiles": m.tiles.len(),
        "largest_tile": largest,
        "duplicates": m.duplicates,
        "skipped_invalid": m.skipped_invalid,
        "bounds_min": m.bounds_min,
        "bounds_max": m.bounds_max,
        "spacing_estimate": m.spacing,
        "columns": m.columns,
        "source": m.source,
    }))
}

fn print_text(v: &serde_json::Value) {
    if let Some(map) = v.as_object() {
        for (k, val) in map {
            if !val.is_null() {
                println!("{:>18}: {}", k, val);
            }
        }
    }
}
