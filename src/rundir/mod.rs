//! Run directories (`--run-dir DIR`): a run that survives a kill, a
//! reboot or a full disk. DIR keeps the point store, the finished tiles of
//! every tile stage (`tiles/`), the results of finished global stages
//! (`stages/`, by [`StageId`]), a log of the processes that worked in it
//! (`log.txt`, and `procs/`: where each works, so a running process is
//! told from a dead one), and what identifies the run (`run.json`: the
//! command line, its working directory, the scanmesh version and a
//! fingerprint of the input). The same identity again resumes; a changed
//! one is refused, or started afresh with `restart`. A [`Session`] is a
//! process's job there (all of it, up to a stage, or some tiles of one),
//! and [`RunStatus`] what the directory says of its run.
//!
//! A run directory is recognised by the marker file scanmesh writes when
//! it takes an empty directory over; a restart removes only the entries
//! scanmesh makes there, and a directory without the marker is refused,
//! never emptied: `--run-dir .` once deleted the input beside it. The
//! small files (`run.json`, `done.json`, `stages/`) are sealed with a
//! CRC-32 of their content, so a damaged one is refused, not misread.
//!
//! What identifies a run's command line (which options do not change its
//! result) is the caller's: the library compares [`RunIdentity::args`]
//! as given.

mod dir;
mod identity;
mod liveness;
mod per_point;
mod processes;
mod script;
mod sealed;
mod session;
mod status;

pub use crate::store::StageId;
pub use dir::{RunDir, MARKER_FILE};
pub use identity::{fingerprint, Difference, Done, Fingerprint, RunIdentity};
pub use liveness::ProcessRecord;
pub use per_point::{Computing, Hear, PointRun, Said};
pub use processes::{Processes, Running};
pub use script::{job_script, this_binary, Scheduler};
pub use session::{open_input, Session};
pub use status::{OutputState, RunStatus, StageTiles, StoreSize};

use crate::io::IoError;
use crate::pipeline::WorkspaceError;
use crate::store::{Causes, StoreError};
use std::path::{Path, PathBuf};

/// Why a run directory cannot be used, or a file in it read or written.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RunDirError {
    /// The run directory cannot be made.
    #[error("--run-dir {}: cannot create it", dir.display())]
    Create {
        /// The directory.
        dir: PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// A path cannot be made absolute (it is empty).
    #[error("{}: not a usable path", path.display())]
    Path {
        /// The path.
        path: PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// A file or directory cannot be read.
    #[error("reading {}", path.display())]
    Read {
        /// The file or directory.
        path: PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// A file or directory cannot be written.
    #[error("writing {}", path.display())]
    Write {
        /// The file or directory.
        path: PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// A restart cannot remove what scanmesh made.
    #[error("--restart: removing {}", path.display())]
    Remove {
        /// The entry.
        path: PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// The directory holds files and is not a run directory.
    #[error("--run-dir {}: not empty and not a scanmesh run directory (it holds {} and no {MARKER_FILE}); scanmesh deletes only what it made, so give an empty or new directory", dir.display(), holds.display())]
    NotARunDirectory {
        /// The directory.
        dir: PathBuf,
        /// One of its entries.
        holds: PathBuf,
    },
    /// The directory holds another run.
    #[error("--run-dir {}: {difference}; to start this run afresh there, add --restart", dir.display())]
    OtherRun {
        /// The directory.
        dir: PathBuf,
        /// How the runs differ.
        difference: Difference,
    },
    /// A small file is not the one scanmesh wrote (its seal fails).
    #[error("{}: damaged (not the file scanmesh wrote): start the run afresh with --restart", path.display())]
    Damaged {
        /// The file.
        path: PathBuf,
    },
    /// The run's store lost its manifest.
    #[error("{}: the run's store has no {} (damaged or removed): start the run afresh with --restart", store.display(), crate::store::manifest::MANIFEST_FILE)]
    StoreWithoutManifest {
        /// The store.
        store: PathBuf,
    },
    /// The run's store fails its checks (a checksum, a column's size).
    #[error("{}: start the run afresh with --restart", dir.display())]
    StoreDamaged {
        /// The run directory.
        dir: PathBuf,
        /// What the store's check found.
        #[source]
        source: StoreError,
    },
    /// A tile job came before the job that builds the store.
    #[error("{}: the run has no store yet: its first job (ingest) must finish before tile jobs", dir.display())]
    NoStoreYet {
        /// The run directory.
        dir: PathBuf,
    },
    /// A tile job named a stage the run never came to.
    #[error("run-job --stage {stage}: the run has no tile stage of that name (see `scanmesh status {}`)", dir.display())]
    NoSuchTileStage {
        /// The stage as the job named it (the user's `--stage` word, which
        /// names no stage: free text, kept as given).
        stage: String,
        /// The run directory.
        dir: PathBuf,
    },
    /// A job was given a directory that does not exist.
    #[error("{}: no such run directory", dir.display())]
    NoSuchDir {
        /// The directory, as the caller named it.
        dir: PathBuf,
    },
    /// A job was given a directory no run was started in.
    #[error("{}: not a run directory (start the run with --run-dir first)", dir.display())]
    NotARun {
        /// The directory, as the caller named it.
        dir: PathBuf,
    },
    /// A job was given a run another version of scanmesh started.
    #[error("{}: the run was started by scanmesh {started}, this is {this}", dir.display())]
    OtherVersion {
        /// The directory, as the caller named it.
        dir: PathBuf,
        /// The version that started the run.
        started: String,
        /// This version.
        this: String,
    },
    /// The input changed since the run started.
    #[error("{}: the input changed since the run started; start it again with --restart", path.display())]
    InputChanged {
        /// The input, as the run recorded it.
        path: PathBuf,
    },
    /// The store cannot be opened, or its tile files read.
    #[error(transparent)]
    Store(#[from] StoreError),
    /// The run cannot start within its settings (memory, places, input).
    #[error(transparent)]
    Workspace(#[from] WorkspaceError),
    /// A small file cannot be written in place.
    #[error(transparent)]
    Io(#[from] IoError),
}

impl RunDirError {
    /// What this error comes down to ([`Causes`]).
    pub fn causes(&self) -> Causes<'_> {
        match self {
            RunDirError::Workspace(w) => w.causes(),
            RunDirError::Store(e) => e.causes(),
            _ => Causes::default(),
        }
    }
}

/// `path` made absolute.
fn absolute(path: &Path) -> Result<PathBuf, RunDirError> {
    std::path::absolute(path).map_err(|source| RunDirError::Path {
        path: path.to_path_buf(),
        source,
    })
}
