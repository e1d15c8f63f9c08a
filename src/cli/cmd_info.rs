//! `scanmesh info`: what a file or a store holds.

use anyhow::{Context, Result};
use clap::{Args, ValueEnum};
use scanmesh::io::inspect::inspect;
use scanmesh::io::InvalidPolicy;
use scanmesh::neighbours::NeighbourParams;
use scanmesh::normals::NormalParams;
use scanmesh::pipeline::plan::{MARGIN_FACTOR, MIN_TILE_POINTS};
use scanmesh::pipeline::{KernelCost, MemoryBudget, MemoryPlan};
use scanmesh::recon::implicit::reconstruct::ImplicitParams;
use scanmesh::store::{is_store, PointStore};
use scanmesh::units::human_bytes;
use serde_json::json;
use std::path::PathBuf;

#[derive(Args)]
pub struct InfoArgs {
    /// A point file (PLY, XYZ/CSV, LAS/LAZ, PCD, optionally .gz) or a store directory.
    input: PathBuf,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
    /// No progress bar.
    #[arg(long, short)]
    quiet: bool,
    /// Print the memory plan of a run over this input instead (tiles,
    /// points per tile, the global pass's mode, bytes per stage), without
    /// running it.
    #[arg(long)]
    plan: bool,
    /// The command whose plan to print (with --plan).
    #[arg(long, value_enum, default_value_t = Planned::Normals)]
    command: Planned,
    /// Memory promise to plan for (with --plan).
    #[arg(long, default_value = "1GiB")]
    mem: String,
    /// Worker threads to plan for (with --plan; default: all cores).
    #[arg(long)]
    threads: Option<usize>,
    /// Plan `reconstruct --closed` (with --plan --command reconstruct).
    #[arg(long)]
    closed: bool,
}

/// Commands `info --plan` can plan.
#[derive(Clone, Copy, ValueEnum)]
enum Planned {
    Normals,
    Reconstruct,
    Neighbors,
}

pub fn run(a: InfoArgs) -> Result<()> {
    if a.plan {
        return print_plan(&a);
    }
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
    let store = PointStore::open_shared(dir)?;
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

/// The plan of a run over `a.input` (points from the store, the header,
/// or a pass over the file when it declares no count).
fn print_plan(a: &InfoArgs) -> Result<()> {
    let mem = scanmesh::units::parse_size(&a.mem).with_context(|| format!("--mem {}", a.mem))?;
    let threads = match a.threads {
        Some(0) => anyhow::bail!("--threads must be at least 1"),
        Some(t) => t,
        None => std::thread::available_parallelism().map_or(1, |n| n.get()),
    };
    let points = if is_store(&a.input) {
        PointStore::open_shared(&a.input)?.len()
    } else {
        let progress = super::progress::progress(a.quiet);
        let r = scanmesh::io::open_reader(&a.input, InvalidPolicy::Reject)?;
        match r.info().declared_count {
            Some(n) => n,
            None => inspect(&a.input, InvalidPolicy::Reject, progress.as_ref())?.count,
        }
    };
    let cost: KernelCost = match a.command {
        Planned::Normals => NormalParams::default().cost(),
        Planned::Reconstruct => ImplicitParams {
            closed: a.closed,
            ..ImplicitParams::default()
        }
        .cost(),
        Planned::Neighbors => NeighbourParams::default().cost(),
    };
    let budget = MemoryBudget::new(mem, threads);
    let minimum = MemoryPlan::minimum_budget(threads, points, &cost);
    let plan = MemoryPlan::new(budget, points, &cost)?;
    println!(
        "plan for {} points, --mem {}, {} threads:",
        points,
        human_bytes(mem),
        threads
    );
    println!("  smallest budget that plans: {}", human_bytes(minimum));
    println!(
        "  tiles: at most {} core points each (at least {MIN_TILE_POINTS}), about {} tiles; {} in flight, margins up to {:.1}x the core",
        plan.tile_points,
        points.div_ceil(plan.tile_points),
        threads + 1,
        MARGIN_FACTOR
    );
    let global = if cost.global_per_point == 0 {
        "none".to_string()
    } else if plan.global_in_memory {
        format!("in memory ({} B/point)", cost.global_per_point)
    } else {
        format!("external (about {} contracted boundary nodes)", plan.nodes)
    };
    println!("  global pass: {global}");
    if cost.resident_per_point > 0.0 {
        println!(
            "  small-piece filter: about {} beside the marching-cubes tiles",
            human_bytes((points as f64 * cost.resident_per_point) as u64)
        );
    }
    for (stage, bytes) in plan.stages(&cost) {
        println!("  {stage:>14}: {}", human_bytes(bytes));
    }
    println!(
        "  fixed costs: {}",
        human_bytes(scanmesh::pipeline::plan::BASE_BYTES)
    );
    Ok(())
}
