//! What a point file or a store holds (`scanmesh info`): one record built
//! from a pass over a file ([`crate::io::inspect`], its spacing measured
//! as it streams past, a LAS file's frame, an E57 file's scans) or from a
//! store's manifest, rendered as JSON or as text; and the points and
//! footprint a run over an input would plan for (`info --plan`).

use super::{run_footprint, Kept, PointStore, RunFootprint, StoreError};
use crate::io::e57::is_e57_magic;
use crate::io::inspect::{inspect, inspect_scans, Inspection, ScanInspection};
use crate::io::{open_reader, Format, LasSource, ReadOptions, Selection};
use crate::memory::KernelCost;
use crate::progress::Progress;
use serde_json::{json, Value};
use std::fmt;
use std::path::Path;

/// What an input holds: a JSON record (keys in name order), shown as is
/// (`info --json`) or as text (its `Display`).
#[derive(Clone, Debug, PartialEq)]
pub struct Description(Value);

impl Description {
    /// The record.
    pub fn json(&self) -> &Value {
        &self.0
    }
}

/// The description of the store in `dir`, from its manifest; a selection
/// of points (`select`, not all) is refused: a store holds the points it
/// was built from.
pub fn describe_store(dir: &Path, select: &Selection) -> Result<Description, StoreError> {
    if !select.is_all() {
        return Err(StoreError::SelectionOfAStore {
            path: dir.to_path_buf(),
        });
    }
    let store = PointStore::open_shared(dir)?;
    let m = &store.manifest();
    let largest = m.tiles.iter().map(|t| t.count).max().unwrap_or(0);
    Ok(Description(json!({
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
    })))
}

/// The description of the point file at `path`, read once with `read`
/// (an E57 file's scans listed; it holds no class or return, so a
/// selection is refused as reading it would refuse it).
pub fn describe_file(
    path: &Path,
    read: ReadOptions,
    progress: &dyn Progress,
) -> Result<Description, StoreError> {
    let (r, scans) = match is_e57(path) {
        true => {
            if !read.select.is_all() {
                open_reader(path, read.clone())?;
            }
            let (r, scans) = inspect_scans(path, read.policy, progress)?;
            (r, Some(scans))
        }
        false => (inspect(path, read, progress)?, None),
    };
    let las = las_json(path, r.info.format)?;
    let copc = las["copc"].as_bool() == Some(true);
    let mut record = file_json(path, &r);
    record["scans"] = scans.as_deref().map_or(Value::Null, scans_json);
    record["las"] = las;
    record["copc"] =
        json!(copc.then_some("yes: a cloud-optimised LAZ (COPC info VLR), read as LAZ"));
    Ok(Description(record))
}

/// The facts of one pass over a file.
fn file_json(path: &Path, r: &Inspection) -> Value {
    json!({
        "path": path.display().to_string(),
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
        "spacing_estimate": r.spacing,
        "las_scale": r.info.las_transform.map(|t| t.scale.to_array()),
        "las_offset": r.info.las_transform.map(|t| t.offset.to_array()),
    })
}

/// The points a run over `input` writing `output` plans for (from the
/// store, the header, or a pass over the file when it declares no count)
/// and its footprint ([`super::run_footprint`], as the run plans it): a
/// store that keeps nothing of its input once built, as every plannable
/// run's does (`rundir::PointRun`; only a mesh of input points keeps their
/// coordinates).
pub fn footprint_to_plan(
    input: &Path,
    read: ReadOptions,
    output: Option<&Path>,
    cost: KernelCost,
    progress: &dyn Progress,
) -> Result<(u64, RunFootprint), StoreError> {
    let footprint = run_footprint(input, read.clone(), Kept::Nothing, output, cost)?;
    let points = match footprint.points {
        Some(n) => n,
        None => inspect(input, read, progress)?.count,
    };
    Ok((points, footprint))
}

/// A LAS/LAZ file's frame: version, point format, its VLRs and EVLRs
/// (user id / record id), whether it carries a CRS and whether it is a COPC
/// (a COPC info VLR, user id "copc", record 1: read as LAZ).
fn las_json(path: &Path, format: Format) -> Result<Value, StoreError> {
    if !matches!(format, Format::Las | Format::Laz) {
        return Ok(Value::Null);
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

/// Whether `path` starts with the E57 signature (a file that cannot be
/// read is left to the inspection to report).
fn is_e57(path: &Path) -> bool {
    use std::io::Read;
    let mut magic = [0u8; 8];
    std::fs::File::open(path)
        .and_then(|mut f| f.read_exact(&mut magic))
        .is_ok_and(|_| is_e57_magic(&magic))
}

fn scans_json(scans: &[ScanInspection]) -> Value {
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

/// The text form: one line per field (name, value), then one per scan.
impl fmt::Display for Description {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut lines = Vec::new();
        if let Some(map) = self.0.as_object() {
            for (k, val) in map {
                if !val.is_null() && k != "scans" {
                    lines.push(format!("{:>18}: {}", k.replace('_', " "), human(val)));
                }
            }
        }
        for s in self.0["scans"].as_array().into_iter().flatten() {
            lines.push(scan_line(s));
        }
        f.write_str(&lines.join("\n"))
    }
}

fn scan_line(s: &Value) -> String {
    let coords = match (s["cartesian"].as_bool(), s["spherical"].as_bool()) {
        (Some(true), Some(true)) => "cartesian+spherical",
        (Some(true), _) => "cartesian",
        _ => "spherical",
    };
    format!(
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
    )
}

/// A value as a person reads it: strings without quotes, numbers to a
/// micrometre of a metre-scale scan (six decimals, trailing zeros dropped;
/// below 0.01 five significant digits), arrays and records inline.
fn human(v: &Value) -> String {
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
