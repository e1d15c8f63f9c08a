//! Where a command's points come from: a store built earlier (`scanmesh
//! tile`), or an input file ingested into a scratch store that is removed
//! when the run ends, successful or not.

use super::{build_store, BuildOptions, PointStore, StoreError};
use crate::io::{open_reader, ReadOptions};
use crate::progress::Progress;
use std::path::{Path, PathBuf};

/// An open store, owning its directory when it is scratch.
#[derive(Debug)]
pub struct Workspace {
    /// The open store.
    pub store: PointStore,
    scratch: Option<(PathBuf, crate::io::cleanup::Registered)>,
}

impl Workspace {
    /// A store that outlives the run (the user's, or a resumable run's).
    pub fn kept(store: PointStore) -> Self {
        Workspace {
            store,
            scratch: None,
        }
    }

    /// Whether the store is scratch (deleted when the workspace is dropped).
    pub fn is_scratch(&self) -> bool {
        self.scratch.is_some()
    }
}

impl Drop for Workspace {
    fn drop(&mut self) {
        if let Some((dir, _)) = &self.scratch {
            let _ = std::fs::remove_dir_all(dir);
        }
    }
}

/// True when `path` is a point store directory.
pub fn is_store(path: &Path) -> bool {
    path.join(super::manifest::MANIFEST_FILE).is_file()
}

/// Opens `input` as a store, or ingests it into a scratch store at `scratch`
/// (`read`: an [`InvalidPolicy`](crate::io::InvalidPolicy) or [`ReadOptions`]).
pub fn open_input(
    input: &Path,
    scratch: &Path,
    opts: &BuildOptions,
    read: impl Into<ReadOptions>,
    progress: &dyn Progress,
) -> Result<Workspace, StoreError> {
    if is_store(input) {
        return Ok(Workspace {
            store: PointStore::open(input)?,
            scratch: None,
        });
    }
    let mut reader = open_reader(input, read)?;
    // Own the directory before building, so a failed or interrupted build
    // is cleaned up too.
    let registered = crate::io::cleanup::register(scratch);
    let guard = ScratchGuard(scratch.to_path_buf());
    let mut store = build_store(reader.as_mut(), scratch, opts, progress)?;
    store.mark_scratch();
    std::mem::forget(guard);
    Ok(Workspace {
        store,
        scratch: Some((scratch.to_path_buf(), registered)),
    })
}

/// Ingests `input` into a store at `dir` that outlives the run (a
/// resumable run's): built under a name beside it and renamed, so `dir` is
/// a whole store or absent, and a killed build is simply redone.
pub fn ingest_kept(
    input: &Path,
    dir: &Path,
    opts: &BuildOptions,
    read: impl Into<ReadOptions>,
    progress: &dyn Progress,
) -> Result<(), StoreError> {
    let partial = dir.with_extension("partial");
    if partial.exists() {
        std::fs::remove_dir_all(&partial).map_err(|e| StoreError::os(&partial, e))?;
    }
    let _registered = crate::io::cleanup::register(&partial);
    let guard = ScratchGuard(partial.clone());
    let mut reader = open_reader(input, read)?;
    drop(build_store(reader.as_mut(), &partial, opts, progress)?);
    std::fs::rename(&partial, dir).map_err(|e| StoreError::os(dir, e))?;
    std::mem::forget(guard);
    Ok(())
}

struct ScratchGuard(PathBuf);

impl Drop for ScratchGuard {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::{Format, WriterSpec};
    use crate::store::{export_points_keeping, Kept, Rows};

    /// A scratch store gives up its positions once its stages are done:
    /// their disk is freed, a read of them is an error (not a fault), and
    /// the export, which never reads them, writes every point; a store
    /// that outlives the run keeps them.
    #[test]
    fn a_scratch_store_frees_its_positions_and_still_exports() {
        let tmp = tempfile::tempdir().unwrap();
        let input = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/las/autzen.las");
        let opts = BuildOptions {
            keep: Kept::Nothing,
            ..BuildOptions::default()
        };
        let nop = &crate::progress::NoProgress;
        let read = ReadOptions::default();
        let mut ws = open_input(&input, &tmp.path().join("s"), &opts, read.clone(), nop).unwrap();
        let store = &mut ws.store;
        let (start, count) = (store.tiles()[0].start, store.tiles()[0].count);
        store.release_positions().unwrap();
        let xyz = std::fs::metadata(store.dir().join(crate::store::XYZ_FILE)).unwrap();
        assert_eq!(xyz.len(), 0);
        assert!(store.read_coords(start, count, &mut Vec::new()).is_err());
        let out = tmp.path().join("out.xyz");
        let rows = Rows {
            output: &out,
            window: 100,
            input: Some((&input, &read)),
            keep_unselected: false,
            progress: nop,
        };
        let spec = WriterSpec::new(Format::Xyz);
        assert_eq!(
            export_points_keeping(store, &spec, &rows).unwrap(),
            store.len()
        );
        // Built for keeps: nothing is given up.
        let dir = tmp.path().join("kept");
        let mut reader = crate::io::open_reader(&input, read).unwrap();
        let mut kept = crate::store::build_store(reader.as_mut(), &dir, &opts, nop).unwrap();
        kept.release_positions().unwrap();
        assert!(kept.read_coords(start, count, &mut Vec::new()).is_ok());
    }
}
