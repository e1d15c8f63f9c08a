//! `--run-dir DIR`: a run that survives a kill, a reboot or a full disk.
//! DIR keeps the point store, the finished tiles of every tile stage
//! (`tiles/`), the results of finished global stages (`stages/`), a log of
//! the processes that worked in it (`log.txt`), and what identifies the
//! run (`run.json`: the command line, its working directory, the
//! scanmesh version and a fingerprint of the input). The same command line
//! again resumes; a changed input or command line is refused, or started
//! afresh with `--restart`. `run-job` does a part of a run (`--emit`
//! writes the scripts that call it), `status` reads DIR.

use super::Command;
use anyhow::{anyhow, bail, Context, Result};
use scanmesh::io::atomic::AtomicFile;
use scanmesh::store::{checkpoint, Checkpoints, Job};
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use std::io::{Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

const RUN_FILE: &str = "run.json";
const DONE_FILE: &str = "done.json";
const LOG_FILE: &str = "log.txt";

/// Options that vary between the processes of one run without changing
/// its result, with whether each takes a value: left out of the
/// comparison of command lines.
const VOLATILE: [(&str, bool); 8] = [
    ("--quiet", false),
    ("-q", false),
    ("--threads", true),
    ("--report", true),
    ("--restart", false),
    ("--emit", true),
    ("--tasks", true),
    ("--run-dir", true),
];

/// The checkpoints of this process's store: where the job says it stopped.
static WATCHED: std::sync::Mutex<Option<Checkpoints>> = std::sync::Mutex::new(None);

/// Remembers `c` so [`run_in_dir`] learns whether the job stopped as asked.
pub fn watch(c: &Checkpoints) {
    if let Ok(mut w) = WATCHED.lock() {
        *w = Some(c.clone());
    }
}

fn stopped_at() -> Option<String> {
    let w = WATCHED.lock().ok()?;
    w.as_ref()?.stopped_at().map(str::to_string)
}

/// Runs `command` (given as `args`), in its run directory when it has one:
/// starts or resumes the run there, or prints its job script (`--emit`),
/// or says there is nothing left to do.
pub fn run_in_dir(command: Command, args: Vec<String>) -> Result<()> {
    let Some(common) = command.common() else {
        return super::dispatch(command);
    };
    let Some(dir) = common.run_dir.clone() else {
        return super::dispatch(command);
    };
    let (input, output) = command
        .paths()
        .map(|(i, o)| (i.to_path_buf(), o.to_path_buf()))
        .ok_or_else(|| {
            anyhow!("--run-dir is for normals, neighbors, reconstruct, curvature and features")
        })?;
    let run = RunDir::new(&dir)?;
    let job = common.job.clone();
    if job == Job::Whole {
        let id = RunIdentity {
            scanmesh_version: env!("CARGO_PKG_VERSION").to_string(),
            args: stable_args(&args),
            cwd: std::env::current_dir()?,
            input: fingerprint(&input)?,
        };
        run.begin(&id, common.restart)?;
        if let Some(kind) = common.emit {
            let stages = command.tile_stages()?;
            let settings = common.settings()?;
            print!(
                "{}",
                super::emit::script(kind, &run, &stages, common.tasks, &settings)
            );
            return Ok(());
        }
        if let Some(summary) = run.finished(&output) {
            super::report::summary(format!(
                "nothing to do: {} is complete ({})",
                output.display(),
                run.dir.display()
            ));
            if !summary.is_empty() && !common.quiet {
                println!("  {summary}");
            }
            return Ok(());
        }
    }
    let what = job_text(&job);
    run.log(&format!("start {what}"));
    let outcome = super::dispatch(command);
    let outcome = match (outcome, stopped_at(), &job) {
        (Err(_), Some(stage), _) => {
            run.log(&format!("done {what} (stopped at {stage}), peak {}", super::peak()));
            return Ok(());
        }
        (Ok(()), None, Job::Tiles { stage, .. }) => Err(anyhow!(
            "run-job --stage {stage}: the run has no tile stage of that name (see `scanmesh status {}`)",
            run.dir.display()
        )),
        (outcome, ..) => outcome,
    };
    match &outcome {
        Ok(()) => {
            // An `--until` job that found no stage to stop at ran it all.
            if !matches!(job, Job::Tiles { .. }) {
                run.finish(&output, super::report::last_summary())?;
            }
            run.log(&format!("done {what}, peak {}", super::peak()));
        }
        Err(e) => run.log(&format!("failed {what}: {e:#}")),
    }
    outcome
}

/// A job in words, for the log.
pub fn job_text(job: &Job) -> String {
    match job {
        Job::Whole => "run".to_string(),
        Job::Until(s) => format!("job --until {s}"),
        Job::Tiles { stage, tiles } => format!("job --stage {stage} {tiles}"),
    }
}

/// What identifies a run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunIdentity {
    pub scanmesh_version: String,
    /// The command line without program name and volatile options.
    pub args: Vec<String>,
    /// Where relative paths in `args` start.
    pub cwd: PathBuf,
    pub input: Fingerprint,
}

/// Size, modification time and a hash of the header and some blocks of
/// the input (of its manifest when the input is a store).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Fingerprint {
    pub path: PathBuf,
    pub bytes: u64,
    pub modified_ns: u128,
    pub sampled_hash: String,
}

/// What a finished run wrote.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct Done {
    output: PathBuf,
    output_bytes: u64,
    summary: Option<String>,
}

/// The parts of `args` that decide a run's result.
pub fn stable_args(args: &[String]) -> Vec<String> {
    let mut out = Vec::new();
    let mut skip_value = false;
    for a in args {
        if std::mem::take(&mut skip_value) {
            continue;
        }
        let name = a.split('=').next().unwrap_or(a);
        match VOLATILE.iter().find(|(v, _)| *v == name) {
            Some((_, takes)) => skip_value = *takes && !a.contains('='),
            None => out.push(a.clone()),
        }
    }
    out
}

pub fn fingerprint(input: &Path) -> Result<Fingerprint> {
    let file = if input.is_dir() {
        input.join(scanmesh::store::manifest::MANIFEST_FILE)
    } else {
        input.to_path_buf()
    };
    let meta = std::fs::metadata(&file).with_context(|| format!("reading {}", file.display()))?;
    let modified_ns = meta
        .modified()
        .ok()
        .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
        .map_or(0, |d| d.as_nanos());
    Ok(Fingerprint {
        path: std::path::absolute(input)?,
        bytes: meta.len(),
        modified_ns,
        sampled_hash: format!("{:016x}", sampled_hash(&file, meta.len())?),
    })
}

/// FNV-1a over the first and last 64 KiB and 16 blocks of 4 KiB spread
/// between: catches a rewritten file whose size and time were kept.
fn sampled_hash(path: &Path, len: u64) -> Result<u64> {
    let mut f = std::fs::File::open(path).with_context(|| format!("reading {}", path.display()))?;
    let mut offsets = vec![(0, 65_536)];
    offsets.extend((1..=16).map(|i| (len / 17 * i, 4096)));
    offsets.push((len.saturating_sub(65_536), 65_536));
    let mut h = checkpoint::FNV_SEED;
    let mut buf = Vec::new();
    for (at, n) in offsets {
        buf.clear();
        f.seek(SeekFrom::Start(at.min(len)))?;
        (&mut f).take(n).read_to_end(&mut buf)?;
        h = buf
            .iter()
            .fold(h, |h, &b| (h ^ b as u64).wrapping_mul(0x0100_0000_01b3));
    }
    Ok(h)
}

/// A run directory.
#[derive(Clone, Debug)]
pub struct RunDir {
    pub dir: PathBuf,
}

impl RunDir {
    pub fn new(dir: &Path) -> Result<Self> {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("--run-dir {}: cannot create it", dir.display()))?;
        Ok(RunDir {
            dir: std::path::absolute(dir)?,
        })
    }

    pub fn store_dir(&self) -> PathBuf {
        self.dir.join("store")
    }

    pub fn tiles_dir(&self) -> PathBuf {
        self.dir.join("tiles")
    }

    /// Starts or resumes the run `id` here: a directory of another run
    /// (other command line, changed input, other version) is refused, or
    /// emptied first with `restart`.
    pub fn begin(&self, id: &RunIdentity, restart: bool) -> Result<()> {
        if restart {
            self.clear()?;
        }
        match self.identity()? {
            None => {
                if std::fs::read_dir(&self.dir)?.next().is_some() {
                    bail!(
                        "--run-dir {}: not empty and not a scanmesh run directory (give an empty or new directory)",
                        self.dir.display()
                    );
                }
                write_atomic(&self.dir.join(RUN_FILE), &serde_json::to_vec_pretty(id)?)
            }
            Some(old) if old == *id => Ok(()),
            Some(old) => bail!(
                "--run-dir {}: {}; to start this run afresh there, add --restart",
                self.dir.display(),
                difference(&old, id)
            ),
        }
    }

    /// The identity recorded in this directory.
    pub fn identity(&self) -> Result<Option<RunIdentity>> {
        let path = self.dir.join(RUN_FILE);
        match std::fs::read(&path) {
            Ok(bytes) => Ok(Some(serde_json::from_slice(&bytes).with_context(|| {
                format!("{}: not a scanmesh run file", path.display())
            })?)),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
            Err(e) => Err(e).with_context(|| format!("reading {}", path.display())),
        }
    }

    fn clear(&self) -> Result<()> {
        for entry in std::fs::read_dir(&self.dir)? {
            let path = entry?.path();
            if path.is_dir() {
                std::fs::remove_dir_all(&path)
            } else {
                std::fs::remove_file(&path)
            }
            .with_context(|| format!("--restart: removing {}", path.display()))?;
        }
        Ok(())
    }

    /// The summary of a finished run whose output is still there, whole.
    pub fn finished(&self, output: &Path) -> Option<String> {
        let done: Done =
            serde_json::from_slice(&std::fs::read(self.dir.join(DONE_FILE)).ok()?).ok()?;
        let bytes = std::fs::metadata(output).ok()?.len();
        let same = std::path::absolute(output).ok()? == done.output && bytes == done.output_bytes;
        same.then(|| done.summary.unwrap_or_default())
    }

    /// Records that the run wrote `output`.
    pub fn finish(&self, output: &Path, summary: Option<String>) -> Result<()> {
        let done = Done {
            output: std::path::absolute(output)?,
            output_bytes: std::fs::metadata(output)?.len(),
            summary,
        };
        write_atomic(
            &self.dir.join(DONE_FILE),
            &serde_json::to_vec_pretty(&done)?,
        )
    }

    /// The saved result of the global stage `name`, if it finished.
    pub fn stage<T: DeserializeOwned>(&self, name: &str) -> Option<T> {
        let bytes = std::fs::read(self.stage_path(name)).ok()?;
        serde_json::from_slice(&bytes).ok()
    }

    /// Saves the result of the global stage `name`: it is not redone.
    pub fn keep_stage<T: Serialize>(&self, name: &str, value: &T) -> Result<()> {
        let path = self.stage_path(name);
        if let Some(dir) = path.parent() {
            std::fs::create_dir_all(dir)?;
        }
        write_atomic(&path, &serde_json::to_vec_pretty(value)?)
    }

    fn stage_path(&self, name: &str) -> PathBuf {
        self.dir.join("stages").join(format!("{name}.json"))
    }

    /// Appends a line to the run log (best effort: the log is for people).
    pub fn log(&self, line: &str) {
        let secs = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_secs());
        if let Ok(mut f) = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(self.dir.join(LOG_FILE))
        {
            let _ = writeln!(f, "{secs} pid {} {line}", std::process::id());
        }
    }

    pub fn log_lines(&self) -> Vec<String> {
        std::fs::read_to_string(self.dir.join(LOG_FILE))
            .map(|t| t.lines().map(str::to_string).collect())
            .unwrap_or_default()
    }
}

/// What changed between two identities, in words.
fn difference(old: &RunIdentity, new: &RunIdentity) -> String {
    if old.scanmesh_version != new.scanmesh_version {
        return format!(
            "it holds a run of scanmesh {} (this is {})",
            old.scanmesh_version, new.scanmesh_version
        );
    }
    if old.args != new.args {
        return format!(
            "it holds the run `scanmesh {}`, not `scanmesh {}`",
            old.args.join(" "),
            new.args.join(" ")
        );
    }
    if old.input != new.input {
        return format!(
            "the input {} changed since the run started (size, time or content)",
            new.input.path.display()
        );
    }
    format!(
        "it was started in {}, not {}",
        old.cwd.display(),
        new.cwd.display()
    )
}

/// Writes `bytes` to `path` whole or not at all.
fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let mut file = AtomicFile::create(path)?;
    file.file()
        .write_all(bytes)
        .with_context(|| format!("writing {}", path.display()))?;
    Ok(file.commit()?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn volatile_options_do_not_change_a_run() {
        let args = |s: &str| s.split(' ').map(String::from).collect::<Vec<_>>();
        let a = stable_args(&args(
            "normals in.ply -o out.ply --threads 2 -q --run-dir d --k 9",
        ));
        let b = stable_args(&args(
            "normals in.ply -o out.ply --run-dir=d --report r.json --k 9",
        ));
        assert_eq!(a, b);
        assert_eq!(a, args("normals in.ply -o out.ply --k 9"));
    }
}
