//! `scanmesh status DIR`: what a run directory holds: the run, the store,
//! each tile stage's tiles done (with the time left, from the rate the
//! finished tiles arrived at), the output, and the failures in its log.
//! It only reads, so it works while jobs run.

use super::rundir::{fingerprint, RunDir};
use super::stdout::outln;
use anyhow::{bail, Result};
use clap::Args;
use scanmesh::store::manifest::{Manifest, MANIFEST_FILE};
use std::path::{Path, PathBuf};
use std::time::SystemTime;

#[derive(Args)]
pub struct StatusArgs {
    /// Run directory.
    dir: PathBuf,
}

pub fn run(a: StatusArgs) -> Result<()> {
    let run = RunDir::new(&a.dir)?;
    let Some(id) = run.identity()? else {
        bail!("{}: not a run directory", a.dir.display());
    };
    outln!(
        "run: scanmesh {} (in {})",
        id.args.join(" "),
        id.cwd.display()
    )?;
    let unchanged = fingerprint(&id.input.path).is_ok_and(|f| f == id.input);
    outln!(
        "input: {} ({})",
        id.input.path.display(),
        if unchanged {
            "unchanged"
        } else {
            "CHANGED or gone: the run cannot go on"
        }
    )?;
    let tiles = match store_manifest(&run.store_dir()) {
        Some(m) => {
            outln!("store: {} points in {} tiles", m.count, m.tiles.len())?;
            m.tiles.len()
        }
        None => {
            outln!("store: not built yet")?;
            0
        }
    };
    for (stage, times) in stages(&run.tiles_dir()) {
        outln!("stage {stage}: {}", progress(times, tiles))?;
    }
    let log = run.log_lines();
    let failures: Vec<&String> = log.iter().filter(|l| l.contains(" failed ")).collect();
    let started = log.iter().filter(|l| l.contains(" start ")).count();
    outln!(
        "log: {started} processes started, {} failed",
        failures.len()
    )?;
    if let Some(last) = failures.last() {
        outln!("  last failure: {last}")?;
    }
    match log.iter().rev().find(|l| l.contains(" done run")) {
        Some(_) => outln!("output: written")?,
        None => outln!("output: not written yet")?,
    }
    Ok(())
}

fn store_manifest(dir: &Path) -> Option<Manifest> {
    serde_json::from_slice(&std::fs::read(dir.join(MANIFEST_FILE)).ok()?).ok()
}

/// Each tile stage's directory name and the times its tiles were finished.
fn stages(dir: &Path) -> Vec<(String, Vec<SystemTime>)> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    let mut stages: Vec<(String, Vec<SystemTime>)> = entries
        .flatten()
        .map(|e| {
            let times = std::fs::read_dir(e.path())
                .into_iter()
                .flatten()
                .flatten()
                .filter(|f| f.file_name().to_string_lossy().ends_with(".tile"))
                .filter_map(|f| f.metadata().ok()?.modified().ok())
                .collect();
            (e.file_name().to_string_lossy().into_owned(), times)
        })
        .collect();
    stages.sort_by_key(|(_, t)| t.iter().min().copied());
    stages
}

/// "40 of 128 tiles, about 1 min left".
fn progress(mut times: Vec<SystemTime>, total: usize) -> String {
    let done = times.len();
    let mut text = format!("{done} of {total} tiles");
    times.sort();
    if let (Some(first), Some(last)) = (times.first(), times.last()) {
        let span = last
            .duration_since(*first)
            .unwrap_or_default()
            .as_secs_f64();
        if done > 1 && done < total && span > 0.0 {
            let left = span / (done - 1) as f64 * (total - done) as f64;
            text += &format!(", about {} left at the rate so far", human_secs(left));
        }
    }
    text
}

fn human_secs(s: f64) -> String {
    match s {
        s if s < 90.0 => format!("{s:.0} s"),
        s if s < 5400.0 => format!("{:.0} min", s / 60.0),
        s => format!("{:.1} h", s / 3600.0),
    }
}
