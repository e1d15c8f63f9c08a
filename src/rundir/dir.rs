//! A run directory's layout and its files: the marker that makes a
//! directory a run's, starting or resuming a run there (`--restart`
//! removes only what scanmesh made), the identity and done files, the
//! global stages' results and the log.

use super::identity::{fingerprint, Done, RunIdentity};
use super::sealed::{read_sealed, write_atomic, write_sealed};
use super::{liveness::PROCS_DIR, RunDirError};
use crate::store::{is_store, PointStore, StageId};
use serde::de::DeserializeOwned;
use serde::Serialize;
use std::io::Write;
use std::path::{Path, PathBuf};

const RUN_FILE: &str = "run.json";
const DONE_FILE: &str = "done.json";
const LOG_FILE: &str = "log.txt";
/// The file that makes a directory a run directory.
pub const MARKER_FILE: &str = ".scanmesh-run";
const MARKER_TEXT: &str =
    "scanmesh run directory (scanmesh --restart removes only what it made here)\n";
const STORE_DIR: &str = "store";
const TILES_DIR: &str = "tiles";
const STAGES_DIR: &str = "stages";

/// Every entry scanmesh makes in a run directory: all that `--restart`
/// may remove (with the temporaries of their atomic writes).
const MADE: [&str; 9] = [
    PROCS_DIR,
    RUN_FILE,
    DONE_FILE,
    LOG_FILE,
    STORE_DIR,
    "store.partial",
    TILES_DIR,
    STAGES_DIR,
    MARKER_FILE,
];

/// A run directory.
#[derive(Clone, Debug)]
pub struct RunDir {
    dir: PathBuf,
}

impl RunDir {
    /// The run recorded in the directory `dir` (named as the caller
    /// spelled it, for the errors), for a job of it by scanmesh `version`:
    /// refused when it is no run directory, or another version started it.
    pub fn recorded(dir: &Path, version: &str) -> Result<(Self, RunIdentity), RunDirError> {
        if !dir.is_dir() {
            return Err(RunDirError::NoSuchDir {
                dir: dir.to_path_buf(),
            });
        }
        let run = RunDir::at(dir)?;
        let Some(id) = run.identity()? else {
            return Err(RunDirError::NotARun {
                dir: dir.to_path_buf(),
            });
        };
        if id.scanmesh_version != version {
            return Err(RunDirError::OtherVersion {
                dir: dir.to_path_buf(),
                started: id.scanmesh_version,
                this: version.to_string(),
            });
        }
        Ok((run, id))
    }

    /// The run directory `dir`, made when it does not exist yet.
    pub fn create(dir: &Path) -> Result<Self, RunDirError> {
        std::fs::create_dir_all(dir).map_err(|source| RunDirError::Create {
            dir: dir.to_path_buf(),
            source,
        })?;
        Self::at(dir)
    }

    /// The run directory `dir`, as it is (nothing is made).
    pub fn at(dir: &Path) -> Result<Self, RunDirError> {
        Ok(RunDir {
            dir: super::absolute(dir)?,
        })
    }

    /// The directory, absolute.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Where the run's point store is (when its input is a file).
    pub fn store_dir(&self) -> PathBuf {
        self.dir.join(STORE_DIR)
    }

    /// Where the tile stages' finished tiles are.
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
    pub fn begin(&self, id: &RunIdentity, restart: bool) -> Result<(), RunDirError> {
        if !self.is_marked() {
            if let Some(entry) = self.entries()?.next() {
                return Err(RunDirError::NotARunDirectory {
                    dir: self.dir.clone(),
                    holds: PathBuf::from(entry.file_name()),
                });
            }
            self.mark()?;
        } else if restart {
            self.clear()?;
            self.mark()?;
        }
        let Some(old) = self.identity()? else {
            return write_sealed(&self.dir.join(RUN_FILE), id);
        };
        match id.difference(&old) {
            None => Ok(()),
            Some(difference) => Err(RunDirError::OtherRun {
                dir: self.dir.clone(),
                difference,
            }),
        }
    }

    fn mark(&self) -> Result<(), RunDirError> {
        write_atomic(&self.dir.join(MARKER_FILE), MARKER_TEXT.as_bytes())
    }

    /// The directory's entries that can be read.
    fn entries(&self) -> Result<impl Iterator<Item = std::fs::DirEntry>, RunDirError> {
        let entries = std::fs::read_dir(&self.dir).map_err(|source| RunDirError::Read {
            path: self.dir.clone(),
            source,
        })?;
        Ok(entries.flatten())
    }

    /// The identity recorded in this directory.
    pub fn identity(&self) -> Result<Option<RunIdentity>, RunDirError> {
        read_sealed(&self.dir.join(RUN_FILE))
    }

    /// Removes what scanmesh made here, and nothing else.
    fn clear(&self) -> Result<(), RunDirError> {
        let read = |source| RunDirError::Read {
            path: self.dir.clone(),
            source,
        };
        for entry in std::fs::read_dir(&self.dir).map_err(read)? {
            let entry = entry.map_err(read)?;
            if !made_by_scanmesh(&entry.file_name().to_string_lossy()) {
                continue;
            }
            let path = entry.path();
            let removed = match entry.file_type().map_err(read)?.is_dir() {
                true => std::fs::remove_dir_all(&path),
                false => std::fs::remove_file(&path),
            };
            removed.map_err(|source| RunDirError::Remove { path, source })?;
        }
        Ok(())
    }

    /// The summary of a finished run whose output is still there as it was
    /// written and whose store is whole; `None` when the run must go on
    /// (the output is gone or was changed since). A run directory damaged
    /// behind the run's back (its store without a manifest, a column that
    /// fails its checksum) is an error, not "nothing to do".
    pub fn finished(&self, output: &Path, input: &Path) -> Result<Option<String>, RunDirError> {
        let Some(done) = self.done()? else {
            return Ok(None);
        };
        if !is_store(input) {
            self.check_store()?;
        }
        let now = fingerprint(output).ok();
        Ok((now.as_ref() == Some(&done.output)).then(|| done.summary.unwrap_or_default()))
    }

    /// Checks the run's store, when it has one, opening it as a run would:
    /// the manifest, the column sizes and every checksum.
    pub fn check_store(&self) -> Result<(), RunDirError> {
        let store = self.store_dir();
        if !store.exists() {
            return Ok(());
        }
        if !is_store(&store) {
            return Err(RunDirError::StoreWithoutManifest { store });
        }
        PointStore::open_shared(&store)
            .map(drop)
            .map_err(|source| RunDirError::StoreDamaged {
                dir: self.dir.clone(),
                source,
            })
    }

    /// Records that the run wrote `output`, with its summary line.
    pub fn finish(&self, output: &Path, summary: Option<String>) -> Result<(), RunDirError> {
        let done = Done {
            output: fingerprint(output)?,
            summary,
        };
        write_sealed(&self.dir.join(DONE_FILE), &done)
    }

    /// What the finished run recorded, if it finished.
    pub fn done(&self) -> Result<Option<Done>, RunDirError> {
        read_sealed(&self.dir.join(DONE_FILE))
    }

    /// The saved result of the global stage `stage`, if it finished; a
    /// damaged one is an error.
    pub fn stage<T: Serialize + DeserializeOwned>(
        &self,
        stage: StageId,
    ) -> Result<Option<T>, RunDirError> {
        read_sealed(&self.stage_path(stage))
    }

    /// Saves the result of the global stage `stage`: it is not redone.
    pub fn keep_stage<T: Serialize>(&self, stage: StageId, value: &T) -> Result<(), RunDirError> {
        let path = self.stage_path(stage);
        let dir = self.dir.join(STAGES_DIR);
        std::fs::create_dir_all(&dir).map_err(|source| RunDirError::Write { path: dir, source })?;
        write_sealed(&path, value)
    }

    fn stage_path(&self, stage: StageId) -> PathBuf {
        self.dir
            .join(STAGES_DIR)
            .join(format!("{}.json", stage.name()))
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

    /// The run log's lines (none when there is no log yet).
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

#[cfg(test)]
mod tests {
    use super::*;

    /// `--restart` clears what scanmesh made and keeps a user's file.
    #[test]
    fn a_restart_removes_only_what_scanmesh_made() {
        let tmp = tempfile::tempdir().expect("tmp");
        let run = RunDir::create(&tmp.path().join("run")).expect("run dir");
        let input = tmp.path().join("in.xyz");
        std::fs::write(&input, b"0 0 0\n").expect("input");
        let id = RunIdentity::new(vec!["normals".into()], tmp.path().into(), &input).expect("id");
        run.begin(&id, false).expect("begin");
        run.keep_stage(StageId::NORMALS, &42_u32).expect("keep");
        std::fs::write(run.dir().join("mine.txt"), b"x").expect("user file");
        std::fs::write(run.dir().join(".log.txt.partial-7"), b"x").expect("temporary");
        let other = RunIdentity {
            args: vec!["neighbors".into()],
            ..id.clone()
        };
        let err = run.begin(&other, false).expect_err("another run");
        assert!(err.to_string().contains("add --restart"), "{err}");
        run.begin(&other, true).expect("restart");
        assert!(run.dir().join("mine.txt").exists());
        assert!(!run.dir().join(".log.txt.partial-7").exists());
        assert_eq!(run.stage::<u32>(StageId::NORMALS).expect("read"), None);
        assert!(run.is_marked());
    }
}
