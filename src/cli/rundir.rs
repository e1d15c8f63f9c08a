//! `--run-dir DIR`: a run that survives a kill, a reboot or a full disk.
//! DIR keeps the point store, the finished tiles of every tile stage
//! (`tiles/`), the results of finished global stages (`stages/`), a log of
//! the processes that worked in it (`log.txt`), and what identifies the
//! run (`run.json`: the command line, its working directory, the
//! scanmesh version and a fingerprint of the input). The same command line
//! again resumes; a changed input or command line is refused, or started
//! afresh with `--restart`. `run-job` does a part of a run (`--emit`
//! writes the scripts that call it), `status` reads DIR.
//!
//! A run directory is recognised by the marker file scanmesh writes when
//! it takes an empty directory over; `--restart` removes only the entries
//! scanmesh makes there ([`MADE`]), and a directory without the marker is
//! refused, never emptied: `--run-dir .` once deleted the input beside it.
//! The small files (`run.json`, `done.json`, `stages/`) are sealed with a
//! CRC-32 of their content, so a damaged one is refused, not misread.

use anyhow::{anyhow, bail, Context, Result};
use scanmesh::io::atomic::AtomicFile;
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use std::io::{Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

const RUN_FILE: &str = "run.json";
const DONE_FILE: &str = "done.json";
const LOG_FILE: &str = "log.txt";
const MARKER_FILE: &str = ".scanmesh-run";
const MARKER_TEXT: &str =
    "scanmesh run directory (scanmesh --restart removes only what it made here)\n";
const STORE_DIR: &str = "store";
const TILES_DIR: &str = "tiles";
const STAGES_DIR: &str = "stages";

/// Every entry scanmesh makes in a run directory: all that `--restart`
/// may remove (with the temporaries of their atomic writes).
const MADE: [&str; 9] = [
    super::liveness::PROCS_DIR,
    RUN_FILE,
    DONE_FILE,
    LOG_FILE,
    STORE_DIR,
    "store.partial",
    TILES_DIR,
    STAGES_DIR,
    MARKER_FILE,
];

/// Options that vary between the processes of one run without changing
/// its result, with whether each takes a value: left out of the
/// comparison of command lines.
const VOLATILE: [(&str, bool); 9] = [
    ("--quiet", false),
    ("-q", false),
    ("--threads", true),
    ("--report", true),
    ("--restart", false),
    ("--emit", true),
    ("--tasks", true),
    ("--run-dir", true),
    ("--scratch", true),
];

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

/// What a finished run wrote: the output as it was then (a file replaced
/// or touched since is written again, not taken as done).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Done {
    /// The output's size, time and sampled hash when the run finished.
    pub output: Fingerprint,
    /// The run's summary line.
    pub summary: Option<String>,
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
        sampled_hash: format!("{:08x}", sampled_hash(&file, meta.len())?),
    })
}

/// CRC-32 over the first and last 64 KiB and 16 blocks of 4 KiB spread
/// between: catches a rewritten file whose size and time were kept.
fn sampled_hash(path: &Path, len: u64) -> Result<u32> {
    let mut f = std::fs::File::open(path).with_context(|| format!("reading {}", path.display()))?;
    let mut offsets = vec![(0, 65_536)];
    offsets.extend((1..=16).map(|i| (len / 17 * i, 4096)));
    offsets.push((len.saturating_sub(65_536), 65_536));
    let mut h = crc32fast::Hasher::new();
    let mut buf = Vec::new();
    for (at, n) in offsets {
        buf.clear();
        f.seek(SeekFrom::Start(at.min(len)))?;
        (&mut f).take(n).read_to_end(&mut buf)?;
        h.update(&buf);
    }
    Ok(h.finalize())
}

/// A run directory.
#[derive(Clone, Debug)]
pub struct RunDir {
    pub dir: PathBuf,
}

impl RunDir {
    /// The run directory `dir`, made when it does not exist yet.
    pub fn create(dir: &Path) -> Result<Self> {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("--run-dir {}: cannot create it", dir.display()))?;
        Self::at(dir)
    }

    /// The run directory `dir`, as it is (nothing is made).
    pub fn at(dir: &Path) -> Result<Self> {
        Ok(RunDir {
            dir: std::path::absolute(dir)?,
        })
    }

    pub fn store_dir(&self) -> PathBuf {
        self.dir.join(STORE_DIR)
    }

    pub fn tiles_dir(&self) -> PathBuf {
        self.dir.join(TILES_DIR)
    }

    /// Whether scanmesh made this directory a run directory.
    pub fn is_marked(&self) -> bool {
        std::fs::read(self.dir.join(MARKER_FILE)).is_ok_and(|b| b == MARKER_TEXT.as_bytes())
    }

    /// Starts or resumes the run `id` here: a directory of another run
    /// (other command line, changed input, other version) is refused, or
    /// cleared of what scanmesh made first with `restart`; a directory
    /// scanmesh did not make is refused unless it is empty.
    pub fn begin(&self, id: &RunIdentity, restart: bool) -> Result<()> {
        if !self.is_marked() {
            if let Some(entry) = std::fs::read_dir(&self.dir)?.flatten().next() {
                bail!(
                    "--run-dir {}: not empty and not a scanmesh run directory (it holds {} and no {MARKER_FILE}); scanmesh deletes only what it made, so give an empty or new directory",
                    self.dir.display(),
                    entry.file_name().to_string_lossy()
                );
            }
            write_atomic(&self.dir.join(MARKER_FILE), MARKER_TEXT.as_bytes())?;
        } else if restart {
            self.clear()?;
            write_atomic(&self.dir.join(MARKER_FILE), MARKER_TEXT.as_bytes())?;
        }
        match self.identity()? {
            None => write_atomic(&self.dir.join(RUN_FILE), &seal(id)?),
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
        read_sealed(&self.dir.join(RUN_FILE))
    }

    /// Removes what scanmesh made here, and nothing else.
    fn clear(&self) -> Result<()> {
        for entry in std::fs::read_dir(&self.dir)? {
            let entry = entry?;
            if !made_by_scanmesh(&entry.file_name().to_string_lossy()) {
                continue;
            }
            let path = entry.path();
            let removed = match entry.file_type()?.is_dir() {
                true => std::fs::remove_dir_all(&path),
                false => std::fs::remove_file(&path),
            };
            removed.with_context(|| format!("--restart: removing {}", path.display()))?;
        }
        Ok(())
    }

    /// The summary of a finished run whose output is still there as it was
    /// written and whose store is whole; `None` when the run must go on
    /// (the output is gone or was changed since). A run directory damaged
    /// behind the run's back (its store without a manifest, a column that
    /// fails its checksum) is an error, not "nothing to do".
    pub fn finished(&self, output: &Path, input: &Path) -> Result<Option<String>> {
        let Some(done) = read_sealed::<Done>(&self.dir.join(DONE_FILE))? else {
            return Ok(None);
        };
        if !scanmesh::store::is_store(input) {
            self.check_store()?;
        }
        let now = fingerprint(output).ok();
        Ok((now.as_ref() == Some(&done.output)).then(|| done.summary.unwrap_or_default()))
    }

    /// Checks the run's store, when it has one, opening it as a run would:
    /// the manifest, the column sizes and every checksum.
    pub fn check_store(&self) -> Result<()> {
        let store = self.store_dir();
        if !store.exists() {
            return Ok(());
        }
        if !scanmesh::store::is_store(&store) {
            bail!(
                "{}: the run's store has no {} (damaged or removed): start the run afresh with --restart",
                store.display(),
                scanmesh::store::manifest::MANIFEST_FILE
            );
        }
        scanmesh::store::PointStore::open_shared(&store)
            .map(drop)
            .with_context(|| {
                format!(
                    "{}: start the run afresh with --restart",
                    self.dir.display()
                )
            })
    }

    /// Records that the run wrote `output`.
    pub fn finish(&self, output: &Path, summary: Option<String>) -> Result<()> {
        let done = Done {
            output: fingerprint(output)?,
            summary,
        };
        write_atomic(&self.dir.join(DONE_FILE), &seal(&done)?)
    }

    /// What the finished run recorded, if it finished.
    pub fn done(&self) -> Result<Option<Done>> {
        read_sealed(&self.dir.join(DONE_FILE))
    }

    /// The saved result of the global stage `name`, if it finished; a
    /// damaged one is an error.
    pub fn stage<T: Serialize + DeserializeOwned>(&self, name: &str) -> Result<Option<T>> {
        read_sealed(&self.stage_path(name))
    }

    /// Saves the result of the global stage `name`: it is not redone.
    pub fn keep_stage<T: Serialize>(&self, name: &str, value: &T) -> Result<()> {
        let path = self.stage_path(name);
        if let Some(dir) = path.parent() {
            std::fs::create_dir_all(dir)?;
        }
        write_atomic(&path, &seal(value)?)
    }

    fn stage_path(&self, name: &str) -> PathBuf {
        self.dir.join(STAGES_DIR).join(format!("{name}.json"))
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

/// Whether `name` is an entry scanmesh makes in a run directory (or the
/// temporary of one, `.NAME.partial-PID`).
fn made_by_scanmesh(name: &str) -> bool {
    MADE.contains(&name)
        || MADE.iter().any(|m| {
            name.strip_prefix('.')
                .and_then(|n| n.strip_prefix(m))
                .is_some_and(|rest| rest.starts_with(".partial-"))
        })
}

/// A small file's content and the CRC-32 of its canonical JSON.
#[derive(Serialize, Deserialize)]
struct Sealed<T> {
    crc32: u32,
    value: T,
}

/// `value` as sealed JSON.
fn seal<T: Serialize>(value: &T) -> Result<Vec<u8>> {
    let crc32 = crc32fast::hash(&serde_json::to_vec(value)?);
    Ok(serde_json::to_vec_pretty(&Sealed { crc32, value })?)
}

/// The sealed value in `path`; `None` when there is no such file, an error
/// naming the file when it is not whole.
fn read_sealed<T: Serialize + DeserializeOwned>(path: &Path) -> Result<Option<T>> {
    let bytes = match std::fs::read(path) {
        Ok(b) => b,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(e).with_context(|| format!("reading {}", path.display())),
    };
    let damaged = || {
        anyhow!(
            "{}: damaged (not the file scanmesh wrote): start the run afresh with --restart",
            path.display()
        )
    };
    let sealed: Sealed<T> = serde_json::from_slice(&bytes).map_err(|_| damaged())?;
    // Floats and maps serialise canonically, so the value's own JSON is
    // the JSON that was sealed.
    match crc32fast::hash(&serde_json::to_vec(&sealed.value)?) == sealed.crc32 {
        true => Ok(Some(sealed.value)),
        false => Err(damaged()),
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
