//! The point store: a directory holding a JSON manifest beside flat
//! little-endian columns, tile-sorted (see `ARCHITECTURE.md`).
//!
//! Columns: `xyz.f32` (f32 x,y,z relative to the f64 origin), `index.u32`
//! (each point's position in input order), `blocks.f32` (bounds of every
//! `BLOCK` consecutive points of a tile, to find margin points without
//! reading whole neighbour tiles), and attribute columns later passes add
//! (`normal.f32`, `flags.u8`). The store index is the global point id.
//! The input's own attributes (intensity, colour, ...) and its exact
//! coordinates are kept in input order beside them (`intensity.input`,
//! ..., `xyz.input`; see `attributes` and `exact`), and a LAS input's
//! records and frame (`las.input`, `las.head`, `las.tail`; `las_kept`),
//! as much of it as the store keeps (`manifest::Kept`; `reread`). Every column carries
//! checksums, checked on open (`integrity`).

mod attributes;
pub mod build;
mod cells;
pub mod checkpoint;
mod column;
pub(crate) mod columns;
mod damage;
pub mod describe;
mod exact;
pub(crate) mod export;
mod footprint;
mod ingest;
pub mod integrity;
mod las_kept;
pub(crate) mod lock;
pub mod manifest;
mod reorder;
mod reread;
pub(crate) mod sampling;
mod slots;
mod sort;
mod source;
pub mod spacing;
mod stage;
mod tile_plan;

#[cfg(test)]
pub(crate) mod test_store;

pub use attributes::column_file as attribute_file;
pub use build::{build_store, BuildOptions, TileTarget};
pub use checkpoint::{Checkpoints, Job, TileSet, TileSetError};
pub use column::Column;
pub use columns::{ColumnSpec, Item, Provenance, FLAGS, NORMALS};
pub use damage::{ColumnName, DamagedPart};
pub use exact::Coordinates;
pub use export::{
    export_columns, export_points, export_points_keeping, export_values, Computed, Rows,
};
pub use footprint::{output_bytes_per_point, run_footprint, store_bytes_per_point, RunFootprint};
pub use las_kept::LasKept;
pub use manifest::{GridSpec, Kept, Manifest, Station, TileEntry};
pub use source::{ingest_kept, is_store, open_input, Workspace};
pub use stage::StageId;
pub use tile_plan::{plan_tiles, CellCount, PlannedTile, TilePlan};

use crate::geom::Aabb;
use glam::DVec3;
use std::path::{Path, PathBuf};

/// Points per bounds block inside a tile.
pub(crate) const BLOCK: u64 = 512;

pub(crate) const XYZ_FILE: &str = "xyz.f32";
pub(crate) const INDEX_FILE: &str = "index.u32";
pub(crate) const BLOCKS_FILE: &str = "blocks.f32";

/// Errors of the point store; each names the store (or input) path concerned.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum StoreError {
    /// The operating system refused a read or write of `path`.
    #[error("{path}: {source}")]
    Os {
        /// The file read or written.
        path: PathBuf,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
    /// The directory is not a point store this version can read.
    #[error("{path}: not a valid point store: {reason}")]
    Corrupt {
        /// The store directory or file.
        path: PathBuf,
        /// What is wrong with it.
        reason: String,
    },
    /// The input could not be read.
    #[error(transparent)]
    Input(#[from] crate::io::IoError),
    /// The input holds no point.
    #[error("{path}: no points to process")]
    Empty {
        /// The input read.
        path: PathBuf,
    },
    /// The input holds points, but the selection (classes, returns)
    /// kept none of them.
    #[error("{path}: the selection kept no point ({unselected} points not selected)")]
    NoneSelected {
        /// The input read.
        path: PathBuf,
        /// Points the selection left out.
        unselected: u64,
    },
    /// The input holds more points than a store can index.
    #[error("{path}: {count} points exceed the supported {max}")]
    TooMany {
        /// The input read.
        path: PathBuf,
        /// Points found.
        count: u64,
        /// Most points a store holds.
        max: u64,
    },
    /// The spatial index could not be built over the points.
    #[error(transparent)]
    Index(#[from] crate::spatial::IndexError),
    /// A pass needs a column the store does not have.
    #[error("store has no `{column}` column (run the pass that computes it first)")]
    MissingColumn {
        /// The column (its file name, as shown).
        column: ColumnName,
    },
    /// The memory budget cannot hold what the plan needs.
    #[error(transparent)]
    Budget(#[from] crate::memory::BudgetError),
    /// A column or the manifest no longer holds what was written to it.
    #[error("{path}: damaged: {what} fails its checksum (changed since scanmesh wrote it, or corrupted on disk); rebuild the store (`scanmesh tile`) or start the run afresh (--restart)")]
    Damaged {
        /// The file concerned.
        path: PathBuf,
        /// Which part of it (a tile, a range of input points).
        what: DamagedPart,
    },
    /// A selection of points was given for a store.
    #[error("{}: --classes and --returns select points of a point file; a store holds the points it was built from", path.display())]
    SelectionOfAStore {
        /// The store.
        path: PathBuf,
    },
    /// The store keeps nothing of its input in input order
    /// ([`Kept::Nothing`]) and the export was not given the input to read
    /// again.
    #[error("{path}: the store keeps nothing of its input ({source_file}); an export of its points reads the input again and was not given it")]
    InputNotKept {
        /// The store.
        path: PathBuf,
        /// The input it was built from.
        source_file: String,
    },
    /// The input read again for an export is not what the store was
    /// built from (changed, replaced or cut since): the points differ.
    #[error("{path}: changed since the run read it: {what} differ from what was read at the start; nothing was written (run again on the file as it is now)")]
    InputChanged {
        /// The input.
        path: PathBuf,
        /// What differs (a range of points, or the count).
        what: String,
    },
    /// Another process holds the store's lock.
    #[error("{path}: the store is in use by another scanmesh process (try again when it ends)")]
    Busy {
        /// The store directory.
        path: PathBuf,
    },
}

/// What a run's error comes down to where a setting may fix it: a memory
/// budget no plan fits, or the input (a record that is not a point). An
/// error that wraps others says it of its own (`causes`: the store's, a
/// run's workspace, a run directory, the demo), so a caller need not know
/// which wraps which.
#[derive(Clone, Copy, Debug, Default)]
pub struct Causes<'a> {
    /// The budget's error, when it comes down to one.
    pub budget: Option<&'a crate::memory::BudgetError>,
    /// The input's error, when it comes down to one.
    pub input: Option<&'a crate::io::IoError>,
}

impl StoreError {
    /// What this error comes down to ([`Causes`]).
    pub fn causes(&self) -> Causes<'_> {
        match self {
            StoreError::Budget(b) => Causes {
                budget: Some(b),
                input: None,
            },
            StoreError::Input(e) => Causes {
                budget: None,
                input: Some(e),
            },
            _ => Causes::default(),
        }
    }

    pub(crate) fn os(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        StoreError::Os {
            path: path.into(),
            source,
        }
    }
}

/// An open point store.
#[derive(Debug)]
pub struct PointStore {
    dir: PathBuf,
    manifest: Manifest,
    xyz: Column,
    index: Column,
    blocks: Column,
    /// Removed when the run ends (see [`Workspace`]): nothing needs to
    /// reach the disk.
    scratch: bool,
    /// Where finished tiles are kept when the store belongs to a
    /// resumable run (`--run-dir`), and the job of this process.
    checkpoints: Option<Checkpoints>,
    /// The advisory lock held while the store is open.
    _lock: lock::StoreLock,
}

impl PointStore {
    /// Opens the store at `dir` for a run that may add or rewrite columns:
    /// no other process may have it open meanwhile ([`StoreError::Busy`]).
    pub fn open(dir: &Path) -> Result<Self, StoreError> {
        let store = Self::open_locked(dir, lock::StoreLock::exclusive(dir)?)?;
        store.verify()?;
        Ok(store)
    }

    /// Bytes of the store's files on disk (its columns, manifest and LAS
    /// frame; not the run's tiles beside it).
    pub fn bytes_on_disk(&self) -> u64 {
        std::fs::read_dir(&self.dir)
            .map(|entries| {
                entries
                    .flatten()
                    .filter_map(|e| e.metadata().ok())
                    .filter(|m| m.is_file())
                    .map(|m| m.len())
                    .sum()
            })
            .unwrap_or(0)
    }

    /// Opens a store this process has just built: its checksums were
    /// computed from the bytes it wrote, so they are not read back.
    pub(crate) fn open_fresh(dir: &Path, lock: lock::StoreLock) -> Result<Self, StoreError> {
        Self::open_locked(dir, lock)
    }

    /// Opens the store at `dir` to read it only: other readers may have it
    /// open, a run that writes may not.
    pub fn open_shared(dir: &Path) -> Result<Self, StoreError> {
        let store = Self::open_locked(dir, lock::StoreLock::shared(dir)?)?;
        store.verify()?;
        Ok(store)
    }

    fn open_locked(dir: &Path, lock: lock::StoreLock) -> Result<Self, StoreError> {
        let mpath = dir.join(manifest::MANIFEST_FILE);
        let manifest = read_manifest(dir)?;
        if manifest.version != manifest::STORE_VERSION {
            return Err(StoreError::Corrupt {
                path: mpath,
                reason: format!(
                    "store version {} (this scanmesh reads {}): build it again with `scanmesh tile`",
                    manifest.version,
                    manifest::STORE_VERSION
                ),
            });
        }
        let store = PointStore {
            xyz: Column::open(&dir.join(XYZ_FILE), 12, false)?,
            index: Column::open(&dir.join(INDEX_FILE), 4, false)?,
            blocks: Column::open(&dir.join(BLOCKS_FILE), 24, false)?,
            dir: dir.to_path_buf(),
            manifest,
            scratch: false,
            checkpoints: None,
            _lock: lock,
        };
        store.validate()?;
        store.check_attribute_columns()?;
        store.check_las_frame()?;
        store.check_exact_column()?;
        // Later passes size their state by the count: it must be the data's.
        for column in [&store.xyz, &store.index] {
            if column.items()? != store.manifest.count {
                return Err(store.corrupt(format!(
                    "{} holds {} points, the manifest says {}",
                    column.path().display(),
                    column.items()?,
                    store.manifest.count
                )));
            }
        }
        Ok(store)
    }

    /// Checks that the exact coordinates hold every point, or (a store that
    /// keeps nothing of its input) that their checksums cover every point.
    fn check_exact_column(&self) -> Result<(), StoreError> {
        let count = self.manifest.count;
        if self.manifest.kept == manifest::Kept::Nothing {
            let segments = count.div_ceil(integrity::INPUT_SEGMENT);
            if self.manifest.input_sums.len() as u64 != segments {
                return Err(self.corrupt(format!(
                    "{} input checksums for {count} points ({segments} segments)",
                    self.manifest.input_sums.len()
                )));
            }
            return Ok(());
        }
        let exact = Column::open(&self.dir.join(exact::EXACT_FILE), 1, false)?;
        let exact_bytes = self.manifest.coordinates.item_bytes() as u64;
        if exact.items()? != count * exact_bytes {
            return Err(self.corrupt(format!(
                "{} holds {} bytes, {count} points need {}",
                exact.path().display(),
                exact.items()?,
                count * exact_bytes
            )));
        }
        Ok(())
    }

    /// What the store keeps of its input ([`manifest::Kept`]).
    pub fn kept(&self) -> manifest::Kept {
        self.manifest.kept
    }

    /// Fails unless the store keeps its input's exact coordinates (and,
    /// when `whole`, its attributes and records) in input order.
    pub(crate) fn keeps_input(&self, whole: bool) -> Result<(), StoreError> {
        let keeps = match self.manifest.kept {
            manifest::Kept::All => true,
            manifest::Kept::Coordinates => !whole,
            manifest::Kept::Nothing => false,
        };
        match keeps {
            true => Ok(()),
            false => Err(StoreError::InputNotKept {
                path: self.dir.clone(),
                source_file: self.manifest.source.clone(),
            }),
        }
    }

    /// Checks the tile table against the counts: contiguous, complete.
    pub(crate) fn validate(&self) -> Result<(), StoreError> {
        let mut next = 0;
        for (i, t) in self.manifest.tiles.iter().enumerate() {
            if t.start != next {
                return Err(self.corrupt(format!("tile {i} starts at {} not {next}", t.start)));
            }
            next = next
                .checked_add(t.count)
                .ok_or_else(|| self.corrupt(format!("tile {i} holds {} points", t.count)))?;
        }
        if next != self.manifest.count {
            return Err(self.corrupt(format!(
                "tiles hold {next} points, manifest says {}",
                self.manifest.count
            )));
        }
        Ok(())
    }

    fn corrupt(&self, reason: String) -> StoreError {
        StoreError::Corrupt {
            path: self.dir.clone(),
            reason,
        }
    }

    /// Marks the store as scratch: it is deleted at the end of the run.
    pub(crate) fn mark_scratch(&mut self) {
        self.scratch = true;
    }

    /// Whether the store is scratch (deleted at the end of the run).
    pub fn is_scratch(&self) -> bool {
        self.scratch
    }

    /// Frees the disk of the tile-ordered positions (`xyz.f32`,
    /// `blocks.f32`) once a scratch store's stages are done: an export
    /// reads the input order, the computed columns and the input, never
    /// them, and they are 12 of the 46 bytes a point a per-point run's
    /// scratch holds while its output grows. Only a scratch store, which
    /// nothing opens again, gives them up; a later read of them fails.
    pub fn release_positions(&mut self) -> Result<(), StoreError> {
        self.release(&[XYZ_FILE, BLOCKS_FILE])
    }

    /// Frees the disk of every point column of a scratch store whose run
    /// reads no point again: a mesh whose tiles are all meshed writes its
    /// output from their triangles alone, and the positions, normals,
    /// input order and flags (29 bytes a point) would otherwise sit beside
    /// the output while it grows, the peak of the run's disk.
    pub fn release_points(&mut self) -> Result<(), StoreError> {
        let (normals, flags) = (columns::NORMALS.name, columns::FLAGS.name);
        self.release(&[XYZ_FILE, BLOCKS_FILE, INDEX_FILE, normals, flags])
    }

    /// Truncates the files `names` of a scratch store (those it has).
    fn release(&mut self, names: &[&str]) -> Result<(), StoreError> {
        if !self.scratch {
            return Ok(());
        }
        for &name in names {
            let path = self.dir.join(name);
            // A handle of its own: the store's stays open, and truncating
            // frees the blocks now rather than when it closes. `&mut self`:
            // no map of the column is alive.
            match std::fs::File::options().write(true).open(&path) {
                Ok(f) => f.set_len(0).map_err(|e| StoreError::os(&path, e))?,
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => continue,
                Err(e) => return Err(StoreError::os(&path, e)),
            }
            self.manifest.checksums.remove(name);
        }
        Ok(())
    }

    /// Keeps tile results in `checkpoints` (a resumable run).
    pub fn keep_tiles(&mut self, checkpoints: Checkpoints) {
        self.checkpoints = Some(checkpoints);
    }

    /// Where tile results are kept, if this store's run is resumable.
    pub(crate) fn checkpoints(&self) -> Option<&Checkpoints> {
        self.checkpoints.as_ref()
    }

    /// Points in the store.
    pub fn len(&self) -> u64 {
        self.manifest.count
    }

    /// Whether the store holds no point.
    pub fn is_empty(&self) -> bool {
        self.manifest.count == 0
    }

    /// The tiles, in store order.
    pub fn tiles(&self) -> &[TileEntry] {
        &self.manifest.tiles
    }

    /// The f64 origin the f32 stored coordinates are relative to.
    pub fn origin(&self) -> DVec3 {
        DVec3::from_array(self.manifest.origin)
    }

    /// Bounds of all stored points, relative to the origin.
    pub(crate) fn relative_bounds(&self) -> Aabb {
        let mut b = Aabb::EMPTY;
        for t in &self.manifest.tiles {
            b.add(DVec3::from_array(t.points_min.map(f64::from)));
            b.add(DVec3::from_array(t.points_max.map(f64::from)));
        }
        b
    }

    /// How far the distance between two stored points (f32 offsets) may lie
    /// from the distance between the same points as written (the input's
    /// own coordinates, `xyz.input`): each coordinate rounds by up to half
    /// its last place, `|x| 2^-24`, so two points move apart by at most
    /// `2 sqrt(3) max|x| 2^-24`, under `2 max|x| f32::EPSILON`. A kernel
    /// whose exact predicates decide what the written mesh must satisfy
    /// keeps this much clearance (`mesh::clearance`).
    pub(crate) fn rounding_reach(&self) -> f64 {
        let b = self.relative_bounds();
        let max_abs = b.min.abs().max(b.max.abs()).max_element();
        if max_abs.is_finite() {
            2.0 * max_abs * f64::from(f32::EPSILON)
        } else {
            0.0
        }
    }

    /// Stored coordinates (relative to the origin) of points `[first, first+count)`.
    pub fn read_points(
        &self,
        first: u64,
        count: u64,
        out: &mut Vec<DVec3>,
    ) -> Result<(), StoreError> {
        let mut raw = Vec::new();
        self.xyz.read_f32(first, count, &mut raw)?;
        out.clear();
        out.extend(
            raw.chunks_exact(3)
                .map(|c| DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64)),
        );
        Ok(())
    }

    /// Stored coordinates as flat f32 `x, y, z` triples (relative to the
    /// origin), without widening to f64: for passes that read one axis.
    pub fn read_coords(
        &self,
        first: u64,
        count: u64,
        out: &mut Vec<f32>,
    ) -> Result<(), StoreError> {
        self.xyz.read_f32(first, count, out)
    }

    /// Input-order index of points `[first, first+count)`.
    pub fn read_indices(
        &self,
        first: u64,
        count: u64,
        out: &mut Vec<u64>,
    ) -> Result<(), StoreError> {
        self.index.read_u32_wide(first, count, out)
    }

    /// Bounds of blocks `[first, first+count)` (relative to the origin).
    pub(crate) fn read_blocks(
        &self,
        first: u64,
        count: u64,
        out: &mut Vec<Aabb>,
    ) -> Result<(), StoreError> {
        let mut raw = Vec::new();
        self.blocks.read_f32(first, count, &mut raw)?;
        out.clear();
        out.extend(raw.chunks_exact(6).map(|c| {
            Aabb::new(
                DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64),
                DVec3::new(c[3] as f64, c[4] as f64, c[5] as f64),
            )
        }));
        Ok(())
    }

    /// The store's directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The store's description (counts, bounds, tiles, columns).
    pub fn manifest(&self) -> &Manifest {
        &self.manifest
    }

    /// Keeps the sampling statistics a normals pass measured.
    pub(crate) fn set_sampling(
        &mut self,
        stats: sampling::SamplingStats,
    ) -> Result<(), StoreError> {
        self.manifest.sampling = Some(stats);
        self.save_manifest()
    }

    fn save_manifest(&self) -> Result<(), StoreError> {
        save_manifest(&self.dir, &self.manifest)
    }
}

/// Reads and checks the manifest of the store at `dir`: JSON of this
/// layout whose checksum matches (a damaged number, an origin moved by one
/// digit, is refused, not taken).
pub fn read_manifest(dir: &Path) -> Result<Manifest, StoreError> {
    let path = dir.join(manifest::MANIFEST_FILE);
    let text = std::fs::read_to_string(&path).map_err(|e| StoreError::os(&path, e))?;
    let corrupt = |reason: String| StoreError::Corrupt {
        path: path.clone(),
        reason,
    };
    let manifest: Manifest = serde_json::from_str(&text).map_err(|e| corrupt(e.to_string()))?;
    if manifest.version != manifest::STORE_VERSION {
        return Ok(manifest);
    }
    let sum = integrity::manifest_sum(&manifest).map_err(|e| corrupt(e.to_string()))?;
    match manifest.crc32 {
        Some(c) if c == sum => Ok(manifest),
        Some(_) => Err(StoreError::Damaged {
            path,
            what: DamagedPart::Manifest,
        }),
        None => Err(corrupt("the manifest has no checksum".into())),
    }
}

/// Writes the manifest atomically (temp + rename) with its checksum: a
/// store whose manifest exists is complete.
pub(crate) fn save_manifest(dir: &Path, manifest: &Manifest) -> Result<(), StoreError> {
    let path = dir.join(manifest::MANIFEST_FILE);
    let json = |e: serde_json::Error| StoreError::Corrupt {
        path: path.clone(),
        reason: e.to_string(),
    };
    let mut sealed = manifest.clone();
    sealed.crc32 = Some(integrity::manifest_sum(manifest).map_err(json)?);
    let text = serde_json::to_string_pretty(&sealed).map_err(json)?;
    let tmp = dir.join(format!(".{}.tmp", manifest::MANIFEST_FILE));
    std::fs::write(&tmp, text).map_err(|e| StoreError::os(&tmp, e))?;
    std::fs::rename(&tmp, &path).map_err(|e| StoreError::os(&path, e))
}
