//! What identifies a run (its command line as the caller gives it, where
//! it started, the scanmesh version, the input's fingerprint), what a
//! finished run wrote, and what changed between two identities, in words.

use super::RunDirError;
use serde::{Deserialize, Serialize};
use std::io::{Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

/// What identifies a run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunIdentity {
    /// The scanmesh version that started the run.
    pub scanmesh_version: String,
    /// The command line as the caller identifies the run by (the CLI: its
    /// arguments without program name and options that do not change the
    /// result); the library only compares it.
    pub args: Vec<String>,
    /// Where relative paths in `args` start.
    pub cwd: PathBuf,
    /// The input as it was when the run started.
    pub input: Fingerprint,
}

impl RunIdentity {
    /// Refuses the run when its input changed since it started (a
    /// relative path is read from the current directory: the run's `cwd`
    /// for a job).
    pub fn check_input(&self) -> Result<(), RunDirError> {
        if fingerprint(&self.input.path)? != self.input {
            return Err(RunDirError::InputChanged {
                path: self.input.path.clone(),
            });
        }
        Ok(())
    }

    /// The identity of a run of this scanmesh on `input`, by the command
    /// line `args`, started in `cwd`.
    pub fn new(args: Vec<String>, cwd: PathBuf, input: &Path) -> Result<Self, RunDirError> {
        Ok(RunIdentity {
            scanmesh_version: env!("CARGO_PKG_VERSION").to_string(),
            args,
            cwd,
            input: fingerprint(input)?,
        })
    }

    /// What changed from `old` to `self`, if anything.
    pub(super) fn difference(&self, old: &RunIdentity) -> Option<Difference> {
        let d = if old.scanmesh_version != self.scanmesh_version {
            Difference::Version {
                old: old.scanmesh_version.clone(),
                new: self.scanmesh_version.clone(),
            }
        } else if old.args != self.args {
            Difference::Args {
                old: old.args.clone(),
                new: self.args.clone(),
            }
        } else if old.input != self.input {
            Difference::Input {
                path: self.input.path.clone(),
            }
        } else if old.cwd != self.cwd {
            Difference::Cwd {
                old: old.cwd.clone(),
                new: self.cwd.clone(),
            }
        } else {
            return None;
        };
        Some(d)
    }
}

/// Why a run directory holds another run than the one asked for.
#[derive(Clone, Debug, PartialEq)]
pub enum Difference {
    /// Another scanmesh version started it.
    Version {
        /// The version that started it.
        old: String,
        /// This version.
        new: String,
    },
    /// Another command line.
    Args {
        /// The recorded command line.
        old: Vec<String>,
        /// The one given now.
        new: Vec<String>,
    },
    /// The input changed since the run started.
    Input {
        /// The input.
        path: PathBuf,
    },
    /// It was started in another working directory.
    Cwd {
        /// Where it was started.
        old: PathBuf,
        /// Where this one starts.
        new: PathBuf,
    },
}

impl std::fmt::Display for Difference {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Difference::Version { old, new } => {
                write!(f, "it holds a run of scanmesh {old} (this is {new})")
            }
            Difference::Args { old, new } => write!(
                f,
                "it holds the run `scanmesh {}`, not `scanmesh {}`",
                old.join(" "),
                new.join(" ")
            ),
            Difference::Input { path } => write!(
                f,
                "the input {} changed since the run started (size, time or content)",
                path.display()
            ),
            Difference::Cwd { old, new } => write!(
                f,
                "it was started in {}, not {}",
                old.display(),
                new.display()
            ),
        }
    }
}

/// Size, modification time and a hash of the header and some blocks of
/// the input (of its manifest when the input is a store).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Fingerprint {
    /// The file or store, absolute.
    pub path: PathBuf,
    /// Its size.
    pub bytes: u64,
    /// Its modification time, in ns since the epoch (0 when unknown).
    pub modified_ns: u128,
    /// A CRC-32 of its first and last 64 KiB and 16 blocks between, in 8
    /// hex digits.
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

/// The fingerprint of `input` (a file, or a store by its manifest).
pub fn fingerprint(input: &Path) -> Result<Fingerprint, RunDirError> {
    let file = if input.is_dir() {
        input.join(crate::store::manifest::MANIFEST_FILE)
    } else {
        input.to_path_buf()
    };
    let read = |source| RunDirError::Read {
        path: file.clone(),
        source,
    };
    let meta = std::fs::metadata(&file).map_err(read)?;
    let modified_ns = meta
        .modified()
        .ok()
        .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
        .map_or(0, |d| d.as_nanos());
    Ok(Fingerprint {
        path: super::absolute(input)?,
        bytes: meta.len(),
        modified_ns,
        sampled_hash: format!("{:08x}", sampled_hash(&file, meta.len()).map_err(read)?),
    })
}

/// CRC-32 over the first and last 64 KiB and 16 blocks of 4 KiB spread
/// between: catches a rewritten file whose size and time were kept.
fn sampled_hash(path: &Path, len: u64) -> std::io::Result<u32> {
    let mut f = std::fs::File::open(path)?;
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
