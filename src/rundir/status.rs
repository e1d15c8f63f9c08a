//! A run directory's status, as plain data: the run, the store, whether a
//! process works in it (or stopped: killed, its process gone), each tile
//! stage's tiles done (with the time left while one works, from the rate
//! the finished tiles arrived at), the output (there, with the size the
//! run wrote), and the failures in its log. Computing it only reads, so
//! it works while jobs run; [`RunStatus`]'s `Display` is `scanmesh
//! status`'s text.

use super::identity::{fingerprint, RunIdentity};
use super::processes::Processes;
use super::{RunDir, RunDirError};
use crate::store::manifest::{Manifest, MANIFEST_FILE};
use crate::units::human_bytes;
use std::fmt;
use std::path::{Path, PathBuf};
use std::time::SystemTime;

/// What a run directory holds and how far its run got.
#[derive(Clone, Debug)]
pub struct RunStatus {
    /// The run recorded there.
    pub identity: RunIdentity,
    /// Whether the input is as it was when the run started.
    pub input_unchanged: bool,
    /// The run's store (`None`: not built yet).
    pub store: Option<StoreSize>,
    /// The processes working in it, or stopped.
    pub processes: Processes,
    /// Each tile stage's tiles done, in the order they were started.
    pub stages: Vec<StageTiles>,
    /// How many processes the log says started.
    pub started: usize,
    /// The log's lines of failed processes, in order.
    pub failures: Vec<String>,
    /// The output a finished run wrote, and whether it is still there.
    pub output: OutputState,
}

/// The points and tiles of a run's store.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StoreSize {
    /// Points.
    pub points: u64,
    /// Tiles.
    pub tiles: usize,
}

/// How far a tile stage got.
#[derive(Clone, Debug, PartialEq)]
pub struct StageTiles {
    /// The stage's directory name ("marching-cubes").
    pub name: String,
    /// Tiles finished.
    pub done: usize,
    /// The store's tiles.
    pub total: usize,
    /// The time left at the rate so far, in seconds, while a process
    /// works (a stopped run has no rate).
    pub left_secs: Option<f64>,
}

/// The output a finished run wrote, and whether it is still there whole.
#[derive(Clone, Debug, PartialEq)]
pub enum OutputState {
    /// The run has not finished.
    NotYet,
    /// There as the run wrote it, this many bytes.
    Written(PathBuf, u64),
    /// Written, then removed.
    Gone(PathBuf),
    /// Written, then replaced or changed.
    Changed {
        /// The output.
        path: PathBuf,
        /// Its bytes when written.
        was: u64,
        /// Its bytes now.
        now: u64,
    },
}

impl RunStatus {
    /// The status of `run`; `None` when it holds no run.
    pub fn of(run: &RunDir) -> Result<Option<RunStatus>, RunDirError> {
        let Some(identity) = run.identity()? else {
            return Ok(None);
        };
        let input_unchanged = fingerprint(&identity.input.path).is_ok_and(|f| f == identity.input);
        let store = store_manifest(&run.store_dir()).map(|m| StoreSize {
            points: m.count,
            tiles: m.tiles.len(),
        });
        let total = store.map_or(0, |s| s.tiles);
        let log = run.log_lines();
        let processes = Processes::of(run.dir(), &log);
        let running = processes.any_running();
        let stages = stages(&run.tiles_dir())
            .into_iter()
            .map(|(name, times)| StageTiles::of(name, times, total, running))
            .collect();
        Ok(Some(RunStatus {
            identity,
            input_unchanged,
            store,
            processes,
            stages,
            started: log.iter().filter(|l| l.contains(" start ")).count(),
            failures: log.into_iter().filter(|l| l.contains(" failed ")).collect(),
            output: output_state(run),
        }))
    }
}

impl fmt::Display for RunStatus {
    /// `scanmesh status`'s lines (without a last line break).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let id = &self.identity;
        writeln!(
            f,
            "run: scanmesh {} (in {})",
            id.args.join(" "),
            id.cwd.display()
        )?;
        let input = match self.input_unchanged {
            true => "unchanged",
            false => "CHANGED or gone: the run cannot go on",
        };
        writeln!(f, "input: {} ({input})", id.input.path.display())?;
        match self.store {
            Some(s) => writeln!(f, "store: {} points in {} tiles", s.points, s.tiles)?,
            None => writeln!(f, "store: not built yet")?,
        }
        let finished = matches!(self.output, OutputState::Written(..));
        writeln!(f, "state: {}", self.processes.describe(finished))?;
        for stage in &self.stages {
            writeln!(f, "stage {}: {stage}", stage.name)?;
        }
        let failed = self.failures.len();
        writeln!(
            f,
            "log: {} processes started, {failed} failed",
            self.started
        )?;
        if let Some(last) = self.failures.last() {
            writeln!(f, "  last failure: {last}")?;
        }
        write!(f, "output: {}", self.output)
    }
}

impl StageTiles {
    /// A stage whose tiles were finished at `times`, of `total`.
    fn of(name: String, mut times: Vec<SystemTime>, total: usize, running: bool) -> StageTiles {
        let done = times.len();
        times.sort();
        let span = match (times.first(), times.last()) {
            (Some(first), Some(last)) => last.duration_since(*first).unwrap_or_default(),
            _ => Default::default(),
        }
        .as_secs_f64();
        let left_secs = (running && done > 1 && done < total && span > 0.0)
            .then(|| span / (done - 1) as f64 * (total - done) as f64);
        StageTiles {
            name,
            done,
            total,
            left_secs,
        }
    }
}

impl fmt::Display for StageTiles {
    /// "40 of 128 tiles, about 1 min left at the rate so far".
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} of {} tiles", self.done, self.total)?;
        match self.left_secs {
            Some(s) => write!(f, ", about {} left at the rate so far", human_secs(s)),
            None => Ok(()),
        }
    }
}

impl fmt::Display for OutputState {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let again = "the same command again writes it anew";
        match self {
            OutputState::NotYet => write!(f, "not written yet"),
            OutputState::Written(path, bytes) => {
                write!(f, "written ({}, {})", path.display(), human_bytes(*bytes))
            }
            OutputState::Gone(path) => {
                write!(f, "{} was written but is gone; {again}", path.display())
            }
            OutputState::Changed { path, was, now } => write!(
                f,
                "{} changed since the run wrote it (now {now} bytes, it wrote {was}); {again}",
                path.display()
            ),
        }
    }
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

fn store_manifest(dir: &Path) -> Option<Manifest> {
    serde_json::from_slice(&std::fs::read(dir.join(MANIFEST_FILE)).ok()?).ok()
}

/// Each tile stage's directory name and the times its tiles were finished,
/// the stage whose first tile came first first.
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

fn human_secs(s: f64) -> String {
    match s {
        s if s < 90.0 => format!("{s:.0} s"),
        s if s < 5400.0 => format!("{:.0} min", s / 60.0),
        s => format!("{:.1} h", s / 3600.0),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    #[test]
    fn time_left_only_while_a_process_works() {
        let t0 = SystemTime::UNIX_EPOCH + Duration::from_secs(1_000);
        let times: Vec<SystemTime> = (0..5).map(|i| t0 + Duration::from_secs(10 * i)).collect();
        let working = StageTiles::of("normals".into(), times.clone(), 9, true);
        assert_eq!(
            working.to_string(),
            "5 of 9 tiles, about 40 s left at the rate so far"
        );
        let stopped = StageTiles::of("normals".into(), times, 9, false);
        assert_eq!(stopped.to_string(), "5 of 9 tiles");
    }
}
