//! `scanmesh info`: what a file or a store holds.

use super::stdout::outln;
use anyhow::{Context, Result};
use clap::{Args, ValueEnum};
use scanmesh::features::params::FeatureParams;
use scanmesh::features::CurvatureParams;
use scanmesh::io::e57::is_e57_magic;
use scanmesh::io::inspect::{inspect, inspect_scans, ScanInspection};
use scanmesh::io::{Format, InvalidPolicy, LasSource, ReadOptions};
use scanmesh::memory::plan::MIN_TILE_POINTS;
use scanmesh::neighbours::NeighbourParams;
use scanmesh::normals::NormalParams;
use scanmesh::pipeline::{KernelCost, MemoryBudget, MemoryPlan};
use scanmesh::recon::implicit::reconstruct::ImplicitParams;
use scanmesh::store::{is_store, PointStore};
use scanmesh::units::human_bytes;
use serde_json::json;
use std::path::PathBuf;

#[derive(Args)]
pub struct InfoArgs {
    /// A point file (PLY, XYZ/CSV, LAS/LAZ, PCD, optionally .gz; E57, whose
    /// scans are listed) or a store directory.
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
    /// Count points with NaN/inf coordinates (and a last line cut short)
    /// as a processing command would drop them with --skip-invalid,
    /// instead of failing (`skipped_invalid`).
    #[arg(long)]
    skip_invalid: bool,
    #[command(flatten)]
    select: super::SelectArgs,
}

impl InfoArgs {
    /// What to do with invalid records (fail, or count them as skipped)
    /// and which points to count (`--classes`, `--returns`).
    fn policy(&self) -> ReadOptions {
        let policy = match self.skip_invalid {
            true => InvalidPolicy::Skip,
            false => InvalidPolicy::Reject,
        };
        ReadOptions {
            policy,
            select: self.select.selection(),
            ..ReadOptions::default()
        }
    }
}

/// Commands `info --plan` can plan.
#[derive(Clone, Copy, ValueEnum)]
enum Planned {
    Normals,
    Reconstruct,
    Neighbors,
    Curvature,
    Features,
    Outliers,
}

pub fn run(a: InfoArgs) -> Result<()> {
    if a.plan {
        return print_plan(&a);
    }
    let report = if is_store(&a.input) {
        if !a.select.selection().is_all() {
            anyhow::bail!(
                "{}: --classes and --returns select points of a point file; a store holds the points it was built from",
                a.input.display()
            );
        }
        store_report(&a.input)?
    } else {
        let progress = super::progress::progress(a.quiet);
        let (r, scans) = match is_e57(&a.input) {
            true => {
                // E57 holds no class or return: a selection is refused here.
                if !a.select.selection().is_all() {
                    scanmesh::io::open_reader(&a.input, a.policy())?;
                }
                let policy = a.policy().policy;
                let (r, scans) = inspect_scans(&a.input, policy, progress.as_ref())?;
                (r, Some(scans))
            }
            false => (inspect(&a.input, a.policy(), progress.as_ref())?, None),
        };
        let las = las_json(&a.input, r.info.format)?;
        let copc = las["copc"].as_bool() == Some(true);
        json!({
            "path": a.input.display().to_string(),
            "format": r.info.format.to_string(),
            "gzip": r.info.gzip,
            "declared_points": r.info.declared_count,
            "points": r.count,
            "skipped_invalid": r.skipped,
            "no_return": r.left_out.no_return,
            "unselected": r.left_out.unselected,
            "has_normals": r.info.has_normals,
            "attributes": r.info.attributes.describe(),
            "bounds_min": r.bounds.min.to_array(),
            "bounds_max": r.bounds.max.to_array(),
            "spacing_estimate": scanmesh::spatial::mean_nearest_distance(&r.first_points),
            "las_scale": r.info.las_transform.map(|t| t.scale.to_array()),
            "las_offset": r.info.las_transform.map(|t| t.offset.to_array()),
            "scans": scans.as_deref().map(scans_json),
            "las": las,
            "copc": copc.then_some("yes: a cloud-optimised LAZ (COPC info VLR), read as LAZ"),
        })
    };
    if a.json {
        outln!("{}", serde_json::to_string_pretty(&report)?)?;
    } else {
        print_text(&report)?;
    }
    Ok(())
}

/// A LAS/LAZ file's frame: version, point format, its VLRs and EVLRs
/// (user id / record id), whether it carries a CRS and whether it is a COPC
/// (a COPC info VLR, user id "copc", record 1: read as LAZ).
fn las_json(path: &std::path::Path, format: Format) -> Result<serde_json::Value> {
    if !matches!(format, Format::Las | Format::Laz) {
        return Ok(serde_json::Value::Null);
    }
    let src = LasSource::read(path)?;
    let (major, minor) = src.version();
    let records: Vec<String> = src
        .record_ids()
        .iter()
        .map(|(user, id)| format!("{user}/{id}"))
        .collect();
    Ok(json!({
        "version": format!("{major}.{minor}"),
        "point_format": src.point_format(),
        "record_length": src.record_len(),
        "vlrs": src.vlr_count(),
        "evlrs": src.evlr_count(),
        "records": records,
        "crs": src.has_crs(),
        "copc": src.is_copc(),
    }))
}

fn store_report(dir: &std::path::Path) -> Result<serde_json::Value> {
    let store = PointStore::open_shared(dir)?;
    let m = &store.manifest();
    let largest = m.tiles.iter().map(|t| t.count).max().unwrap_or(0);
    Ok(json!({
        "path": dir.display().to_string(),
        "format": "store",
        "points": m.count,
        "tiles": m.tiles.len(),
        "largest_tile": largest,
        "duplicates": m.duplicates,
        "skipped_invalid": m.skipped_invalid,
        "no_return": m.left_out.no_return,
        "unselected": m.left_out.unselected,
        "attributes": store.attributes().describe(),
        "bounds_min": m.bounds_min,
        "bounds_max": m.bounds_max,
        "spacing_estimate": m.spacing,
        "columns": m.columns,
        "source": m.source,
    }))
}

/// Whether `path` starts with the E57 signature (a file that cannot be
/// read is left to the inspection to report).
fn is_e57(path: &std::path::Path) -> bool {
    use std::io::Read;
    let mut magic = [0u8; 8];
    std::fs::File::open(path)
        .and_then(|mut f| f.read_exact(&mut magic))
        .is_ok_and(|_| is_e57_magic(&magic))
}

fn scans_json(scans: &[ScanInspection]) -> serde_json::Value {
    scans
        .iter()
        .map(|s| {
            json!({
                "index": s.scan.index,
                "name": s.scan.name,
                "guid": s.scan.guid,
                "records": s.scan.records,
                "points": s.points,
                "invalid": s.skipped,
                "rotation_wxyz": s.scan.pose.rotation,
                "translation": s.scan.pose.translation,
                "cartesian": s.scan.cartesian,
                "spherical": s.scan.spherical,
                "attributes": s.scan.attributes,
                "bounds_min": (s.points > 0).then(|| s.bounds.min.to_array()),
                "bounds_max": (s.points > 0).then(|| s.bounds.max.to_array()),
            })
        })
        .collect()
}

/// A report value as a person reads it: strings without quotes, numbers
/// to a micrometre of a metre-scale scan (six decimals, trailing zeros
/// dropped; below 0.01 five significant digits), arrays and records inline.
fn human(v: &serde_json::Value) -> String {
    use serde_json::Value;
    match v {
        Value::String(s) => s.clone(),
        Value::Number(n) if n.is_f64() => n.as_f64().map_or(n.to_string(), decimal),
        Value::Array(items) => {
            let parts: Vec<String> = items.iter().map(human).collect();
            format!("[{}]", parts.join(", "))
        }
        Value::Object(map) => {
            let parts: Vec<String> = map
                .iter()
                .filter(|(_, v)| !v.is_null())
                .map(|(k, v)| format!("{}: {}", k.replace('_', " "), human(v)))
                .collect();
            parts.join(", ")
        }
        other => other.to_string(),
    }
}

fn decimal(x: f64) -> String {
    if x != 0.0 && x.abs() < 1e-2 {
        return format!("{x:.4e}");
    }
    let fixed = format!("{x:.6}");
    let trimmed = fixed.trim_end_matches('0').trim_end_matches('.');
    trimmed.to_string()
}

fn print_text(v: &serde_json::Value) -> Result<()> {
    if let Some(map) = v.as_object() {
        for (k, val) in map {
            if !val.is_null() && k != "scans" {
                outln!("{:>18}: {}", k.replace('_', " "), human(val))?;
            }
        }
    }
    for s in v["scans"].as_array().into_iter().flatten() {
        let coords = match (s["cartesian"].as_bool(), s["spherical"].as_bool()) {
            (Some(true), Some(true)) => "cartesian+spherical",
            (Some(true), _) => "cartesian",
            _ => "spherical",
        };
        outln!(
            "  scan {} {}: {} records, {} points, {} invalid; pose rotation (w,x,y,z) {} translation {}; {}; attributes {}",
            s["index"],
            s["name"],
            s["records"],
            s["points"],
            s["invalid"],
            s["rotation_wxyz"],
            s["translation"],
            coords,
            s["attributes"]
        )?;
    }
    Ok(())
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
    // The points, and the bytes a point of the store to build takes.
    let (points, store) = if is_store(&a.input) {
        (PointStore::open_shared(&a.input)?.len(), 0)
    } else {
        let progress = super::progress::progress(a.quiet);
        let r = scanmesh::io::open_reader(&a.input, a.policy())?;
        let store = scanmesh::store::store_bytes_per_point(r.info())?;
        match r.info().declared_count {
            Some(n) => (n, store),
            None => (
                inspect(&a.input, a.policy(), progress.as_ref())?.count,
                store,
            ),
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
        Planned::Curvature => CurvatureParams::default().cost(),
        Planned::Features => FeatureParams::default().cost(),
        Planned::Outliers => scanmesh::outliers::OutlierParams::default().cost(),
    };
    let budget = MemoryBudget::new(mem, threads);
    let minimum = MemoryPlan::minimum_budget(threads, points, &cost);
    let plan = MemoryPlan::new(budget, points, &cost)?;
    outln!(
        "plan for {} points, --mem {}, {} threads:",
        points,
        human_bytes(mem),
        threads
    )?;
    outln!("  smallest budget that plans: {}", human_bytes(minimum))?;
    outln!(
        "  tiles: at most {} core points each (at least {MIN_TILE_POINTS}), about {} tiles; {} in flight, margins up to {:.1}x the core",
        plan.tile_points,
        points.div_ceil(plan.tile_points),
        cost.in_flight(threads),
        cost.loaded_per_core(plan.tile_points)
    )?;
    let global = if cost.global_per_point == 0 {
        "none".to_string()
    } else if plan.global_in_memory {
        format!("in memory ({} B/point)", cost.global_per_point)
    } else {
        format!("external (about {} contracted boundary nodes)", plan.nodes)
    };
    outln!("  global pass: {global}")?;
    if cost.resident_per_point > 0.0 {
        outln!(
            "  small-piece filter: about {} beside the marching-cubes tiles",
            human_bytes((points as f64 * cost.resident_per_point) as u64)
        )?;
    }
    for (stage, bytes) in plan.stages(&cost) {
        outln!("  {stage:>14}: {}", human_bytes(bytes))?;
    }
    outln!(
        "  fixed costs: {}",
        human_bytes(scanmesh::memory::BASE_BYTES)
    )?;
    let disk = scanmesh::memory::DiskPlan::new(points, store, &cost);
    outln!(
        "disk at the peak: the store {}, scratch beside it {}, the output {} and scratch beside that {} (about; --scratch-dir puts the first two elsewhere)",
        human_bytes(disk.store),
        human_bytes(disk.scratch),
        human_bytes(disk.output),
        human_bytes(disk.beside_output)
    )?;
    Ok(())
}
