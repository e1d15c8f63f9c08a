//! Scratch files beside a store: created empty (truncating a stale one),
//! read and written at positions, and removed when dropped, so an error or
//! an interrupted pass leaves nothing behind.

use super::IoError;
use std::fs::File;
use std::os::unix::fs::FileExt;
use std::path::{Path, PathBuf};

/// A scratch file removed when dropped.
pub(crate) struct ScratchFile {
    pub(crate) path: PathBuf,
    pub(crate) file: File,
    _cleanup: super::cleanup::Registered,
}

impl ScratchFile {
    pub(crate) fn create(path: PathBuf) -> Result<Self, IoError> {
        let file = File::options()
            .read(true)
            .write(true)
            .create(true)
            .truncate(true)
            .open(&path)
            .map_err(|e| IoError::os(&path, e))?;
        Ok(ScratchFile {
            _cleanup: super::cleanup::register(&path),
            path,
            file,
        })
    }

    pub(crate) fn path(&self) -> &Path {
        &self.path
    }

    pub(crate) fn read_at(&self, buf: &mut [u8], pos: u64) -> Result<(), IoError> {
        self.file
            .read_exact_at(buf, pos)
            .map_err(|e| IoError::os(&self.path, e))
    }

    pub(crate) fn write_at(&self, buf: &[u8], pos: u64) -> Result<(), IoError> {
        self.file
            .write_all_at(buf, pos)
            .map_err(|e| IoError::os(&self.path, e))
    }
}

impl Drop for ScratchFile {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.path);
    }
}
