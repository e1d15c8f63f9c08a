//! Unnamed scratch files beside an output: in its directory, so on its
//! file system, and removed by the OS when closed or on a crash. The mesh
//! writer keeps its faces in one; the audit (and its out-of-core sort,
//! `runs`) its positions, sets and runs; the piece filter and the
//! projection's seam repair their spools.

use std::fs::File;
use std::path::{Path, PathBuf};

/// An unnamed scratch file in the directory of `path` (same file system,
/// removed by the OS when closed or on a crash).
pub(crate) fn scratch_beside(path: &Path) -> std::io::Result<File> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    tempfile::tempfile_in(&dir)
}
