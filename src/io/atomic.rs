//! Output files that appear under their final name only when complete.
//!
//! Everything is written to a temporary sibling (`.name.partial-<pid>`); only
//! [`AtomicFile::commit`] renames it into place. Dropping an uncommitted file
//! (an error, a panic) removes the temporary, so an interrupted run never
//! leaves a truncated file that looks whole. The temporary is locked while
//! its writer lives, so the next run can tell one a killed run left
//! ([`super::reclaim`]).

use super::IoError;
use std::fs::File;
use std::path::{Path, PathBuf};

/// An output file written under a temporary sibling name and renamed into place by [`AtomicFile::commit`].
#[derive(Debug)]
pub struct AtomicFile {
    final_path: PathBuf,
    temp_path: PathBuf,
    file: File,
    committed: bool,
    /// Removed by an interrupt handler if the run stops before the commit.
    _cleanup: super::cleanup::Registered,
}

impl AtomicFile {
    /// Creates the temporary file beside `path` (same directory, so the final
    /// rename never crosses file systems).
    pub fn create(path: &Path) -> Result<Self, IoError> {
        let name = path
            .file_name()
            .ok_or_else(|| IoError::Unsupported {
                path: path.to_path_buf(),
                reason: "output path has no file name".into(),
            })?
            .to_string_lossy();
        let temp_path = path.with_file_name(format!(".{}.partial-{}", name, std::process::id()));
        let file = File::options()
            .read(true)
            .write(true)
            .create(true)
            .truncate(true)
            .open(&temp_path)
            .map_err(|e| IoError::os(path, e))?;
        super::reclaim::hold(&file);
        Ok(AtomicFile {
            final_path: path.to_path_buf(),
            _cleanup: super::cleanup::register(&temp_path),
            temp_path,
            file,
            committed: false,
        })
    }

    /// The temporary file, to write the output into.
    pub fn file(&mut self) -> &mut File {
        &mut self.file
    }

    pub(crate) fn final_path(&self) -> &Path {
        &self.final_path
    }

    /// Where the output is written until the commit (`.name.partial-<pid>` beside the final path).
    pub fn temp_path(&self) -> &Path {
        &self.temp_path
    }

    /// Flushes to disk and renames the temporary into its final name.
    pub fn commit(self) -> Result<(), IoError> {
        let path = self.final_path.clone();
        self.commit_to(&path)
    }

    /// Flushes to disk and renames the temporary to `path` instead of the
    /// name it was created for (an output that is not what was asked for,
    /// kept under a name that says so; same directory).
    pub(crate) fn commit_to(mut self, path: &Path) -> Result<(), IoError> {
        self.file.sync_all().map_err(|e| IoError::os(path, e))?;
        std::fs::rename(&self.temp_path, path).map_err(|e| IoError::os(path, e))?;
        self.committed = true;
        Ok(())
    }
}

impl Drop for AtomicFile {
    fn drop(&mut self) {
        if !self.committed {
            let _ = std::fs::remove_file(&self.temp_path);
        }
    }
}
