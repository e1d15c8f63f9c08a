//! `scanmesh status DIR`: what a run directory holds: the run, the store,
//! whether a process works in it (or stopped: killed, its process gone),
//! each tile stage's tiles done (with the time left while one works, from
//! the rate the finished tiles arrived at), the output (there, with the
//! size the run wrote), and the failures in its log. It only reads, so it
//! works while jobs run.

use super::liveness::{self, Liveness};
use super::rundir::{fingerprint, RunDir};
use super::stdout::outln;
use anyhow::{bail, Result};
use clap::Args;
use scanmesh::store::manifest::{Manifest, MANIFEST_FILE};
use scanmesh::units::human_bytes;
use std::path::{Path, PathBuf};
use std::time::SystemTime;

#[derive(Args)]
pub struct StatusArgs {
    /// Run directory.
    dir: PathBuf,
}

pub fn run(a: StatusArgs) -> Result<()> {
    let run = RunDir::at(&a.dir)?;
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
    let log = run.log_lines();
    let output = output_state(&run);
    let working = processes(&run.dir, &log);
    outln!("state: {}", working.describe(output.is_written()))?;
    for (stage, times) in stages(&run.tiles_dir()) {
        outln!(
            "stage {stage}: {}",
            progress(times, tiles, working.any_running())
        )?;
    }
    let failures: Vec<&String> = log.iter().filter(|l| l.contains(" failed ")).collect();
    let started = log.iter().filter(|l| l.contains(" start ")).count();
    outln!(
        "log: {started} processes started, {} failed",
        failures.len()
    )?;
    if let Some(last) = failures.last() {
        outln!("  last failure: {last}")?;
    }
    outln!("output: {}", output.describe())?;
    Ok(())
}

/// A line of the run log: `SECS pid PID start|done|failed WHAT...`.
struct Event<'a> {
    pid: u32,
    verb: &'a str,
    what: &'a str,
}

fn event(line: &str) -> Option<Event<'_>> {
    let mut fields = line.splitn(5, ' ');
    let (_secs, pid_word) = (fields.next()?, fields.next()?);
    if pid_word != "pid" {
        return None;
    }
    let pid = fields.next()?.parse().ok()?;
    let verb = fields.next()?;
    let what = fields.next().unwrap_or("");
    Some(Event { pid, verb, what })
}

/// The processes that started in the run directory and never said they
/// ended, with what became of each.
struct Working {
    running: Vec<(u32, Liveness)>,
    gone: Vec<u32>,
}

/// The processes that started and never logged their end. One that is
/// gone counts as stopped unless a later process took its work over: the
/// same job again, or a job that starts the run over (the whole run, or
/// the script's first job, `--until`).
fn processes(dir: &Path, log: &[String]) -> Working {
    // (pid, job, taken over)
    let mut open: Vec<(u32, &str, bool)> = Vec::new();
    for e in log.iter().filter_map(|l| event(l)) {
        match e.verb {
            "start" => {
                let starts_over = e.what == "run" || e.what.starts_with("job --until ");
                open.retain(|&(pid, ..)| pid != e.pid);
                for (_, what, taken) in &mut open {
                    *taken |= starts_over || *what == e.what;
                }
                open.push((e.pid, e.what, false));
            }
            "done" | "failed" => open.retain(|&(pid, ..)| pid != e.pid),
            _ => {}
        }
    }
    let mut working = Working {
        running: Vec::new(),
        gone: Vec::new(),
    };
    for (pid, _, taken_over) in open {
        match liveness::check(dir, pid) {
            // Elsewhere and taken over: most likely killed with its node.
            Liveness::Gone | Liveness::Elsewhere(_) if taken_over => {}
            Liveness::Gone => working.gone.push(pid),
            alive => working.running.push((pid, alive)),
        }
    }
    working
}

impl Working {
    fn any_running(&self) -> bool {
        !self.running.is_empty()
    }

    /// "running (process 812)", "stopped (process 812 is gone)", ...
    fn describe(&self, finished: bool) -> String {
        let pids = |v: &[u32]| v.iter().map(u32::to_string).collect::<Vec<_>>().join(", ");
        let gone = match self.gone.as_slice() {
            [] => None,
            [pid] => Some(format!("process {pid} is gone")),
            many => Some(format!("processes {} are gone", pids(many))),
        };
        if self.running.is_empty() {
            return match gone {
                Some(gone) => {
                    format!("stopped ({gone}); the same command (or job script) again resumes")
                }
                None if finished => "finished".to_string(),
                None => "no process works in it now".to_string(),
            };
        }
        let running: Vec<String> = self
            .running
            .iter()
            .map(|(pid, l)| match l {
                Liveness::Elsewhere(host) => format!("{pid} on {host}, not checked from here"),
                _ => pid.to_string(),
            })
            .collect();
        let noun = if running.len() == 1 {
            "process"
        } else {
            "processes"
        };
        let mut text = format!("running ({noun} {})", running.join("; "));
        if let Some(gone) = gone {
            text += &format!("; stopped: {gone}");
        }
        text
    }
}

/// The output a finished run wrote, and whether it is still there whole.
enum OutputState {
    NotYet,
    Written(PathBuf, u64),
    Gone(PathBuf),
    Changed { path: PathBuf, was: u64, now: u64 },
}

fn output_state(run: &RunDir) -> OutputState {
    // A damaged done.json is the run's to refuse; here it is "not yet".
    let Some(done) = run.done().ok().flatten() else {
        return OutputState::NotYet;
    };
    let path = done.output.path.clone();
    match fingerprint(&path) {
        Ok(now) if now == done.output => OutputState::Written(path, now.bytes),
        Ok(now) => OutputState::Changed {
            path,
            was: done.output.bytes,
            now: now.bytes,
        },
        Err(_) => OutputState::Gone(path),
    }
}

impl OutputState {
    fn is_written(&self) -> bool {
        matches!(self, OutputState::Written(..))
    }

    fn describe(&self) -> String {
        let again = "the same command again writes it anew";
        match self {
            OutputState::NotYet => "not written yet".to_string(),
            OutputState::Written(path, bytes) => {
                format!("written ({}, {})", path.display(), human_bytes(*bytes))
            }
            OutputState::Gone(path) => {
                format!("{} was written but is gone; {again}", path.display())
            }
            OutputState::Changed { path, was, now } => format!(
                "{} changed since the run wrote it (now {now} bytes, it wrote {was}); {again}",
                path.display()
            ),
        }
    }
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

/// "40 of 128 tiles, about 1 min left" (the time left only while a
/// process works: a stopped run has no rate).
fn progress(mut times: Vec<SystemTime>, total: usize, running: bool) -> String {
    let done = times.len();
    let mut text = format!("{done} of {total} tiles");
    times.sort();
    if let (Some(first), Some(last)) = (times.first(), times.last()) {
        let span = last
            .duration_since(*first)
            .unwrap_or_default()
            .as_secs_f64();
        if running && done > 1 && done < total && span > 0.0 {
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
