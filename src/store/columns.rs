//! The store's derived columns as typed specs (name, item type, size), and
//! what produced each one (`Provenance`): the kernel, its parameters and the
//! scanmesh version. A pass reuses a column only when its provenance is the
//! one it would record itself; anything else is recomputed.

use super::{Column, PointStore, StoreError};
use serde::{Deserialize, Serialize};

/// What one item of a column holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Item {
    /// Three f32 (a vector), loaded into tiles as `DVec3`.
    Vec3,
    /// `n` f32 values.
    F32(usize),
    /// One byte (flags, classes).
    U8,
}

impl Item {
    /// Bytes per item on disk.
    pub const fn bytes(self) -> usize {
        match self {
            Item::Vec3 => 12,
            Item::F32(n) => 4 * n,
            Item::U8 => 1,
        }
    }
}

/// A column of the store: its file name and what each point's item holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ColumnSpec {
    /// File name of the column in the store directory.
    pub name: &'static str,
    /// What one point's item holds.
    pub item: Item,
}

impl ColumnSpec {
    /// The column `name` of items `item`.
    pub const fn new(name: &'static str, item: Item) -> Self {
        ColumnSpec { name, item }
    }

    /// Bytes per point on disk, and per loaded point when a tile reads it
    /// as stored (a `Vec3` widens to 24 bytes in a tile).
    pub const fn bytes(&self) -> usize {
        self.item.bytes()
    }
}

/// Oriented unit normals (zero where undefined), by store index.
pub const NORMALS: ColumnSpec = ColumnSpec::new("normal.f32", Item::Vec3);
/// The normals pass's per-point flags (`normals::FLAG_*`).
pub const FLAGS: ColumnSpec = ColumnSpec::new("flags.u8", Item::U8);

/// What produced a column: the kernel, its parameters (their `Debug` form,
/// which names every field), and the scanmesh version that ran it.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Provenance {
    /// Name of the kernel that wrote the column.
    pub kernel: String,
    /// Its parameters, in their `Debug` form.
    pub params: String,
    /// The scanmesh version (`CARGO_PKG_VERSION`) that ran it.
    pub version: String,
}

impl Provenance {
    /// `kernel` run with `params` by this build of scanmesh.
    pub fn of(kernel: &str, params: &impl std::fmt::Debug) -> Self {
        Provenance {
            kernel: kernel.to_string(),
            params: format!("{params:?}"),
            version: env!("CARGO_PKG_VERSION").to_string(),
        }
    }
}

impl PointStore {
    /// Whether the store holds the column `spec`.
    pub fn has_column(&self, spec: &ColumnSpec) -> bool {
        self.manifest.columns.iter().any(|c| c == spec.name)
    }

    /// What produced the column `spec`, if the store holds it and knows.
    pub fn provenance(&self, spec: &ColumnSpec) -> Option<&Provenance> {
        match self.has_column(spec) {
            true => self.manifest.provenance.get(spec.name),
            false => None,
        }
    }

    /// Opens the column `spec` for reading and writing; a file whose size
    /// disagrees with the spec and the point count is refused.
    pub fn column(&self, spec: &ColumnSpec) -> Result<Column, StoreError> {
        if !self.has_column(spec) {
            return Err(StoreError::MissingColumn {
                column: super::ColumnName::Computed(spec.name),
            });
        }
        let col = Column::open(&self.dir.join(spec.name), spec.bytes(), true)?;
        match col.items()? {
            n if n == self.manifest.count => Ok(col),
            n => Err(StoreError::Corrupt {
                path: col.path().to_path_buf(),
                reason: format!(
                    "holds {n} items of {} bytes, the store has {} points",
                    spec.bytes(),
                    self.manifest.count
                ),
            }),
        }
    }

    /// Creates (or resets) the column `spec`, zero-filled, and lists it in
    /// the manifest without a provenance or checksums until
    /// [`Self::finish_column`]. The manifest forgets the old column before
    /// its file is reset, so a run killed in between leaves a column that
    /// is recomputed, never one that fails its old checksums.
    pub fn create_column(&mut self, spec: &ColumnSpec) -> Result<Column, StoreError> {
        let was_known = self.manifest.provenance.remove(spec.name).is_some();
        let was_sealed = self.manifest.checksums.remove(spec.name).is_some();
        let is_new = !self.has_column(spec);
        if is_new {
            self.manifest.columns.push(spec.name.to_string());
        }
        if was_known || was_sealed || is_new {
            self.save_manifest()?;
        }
        Column::create(&self.dir.join(spec.name), spec.bytes(), self.manifest.count)
    }

    /// Records that `made_by` produced the column `spec` (once it is
    /// written) with its checksums: later passes may reuse it when they
    /// would make the same, and a later open checks it is unchanged.
    pub fn finish_column(
        &mut self,
        spec: &ColumnSpec,
        column: &Column,
        made_by: Provenance,
    ) -> Result<(), StoreError> {
        self.sync_column(column)?;
        self.seal_column(spec.name, spec.bytes())?;
        self.manifest
            .provenance
            .insert(spec.name.to_string(), made_by);
        self.save_manifest()
    }

    /// Forces a column of this store to disk, unless the store is scratch.
    /// For a scratch store it would cost an fdatasync and, worse, the blocks
    /// it allocates make removing the file slow (ext4: 17-34 ms for the
    /// normals of 1M points, where an unsynced column unlinks in 0.03 ms).
    pub fn sync_column(&self, column: &Column) -> Result<(), StoreError> {
        if self.scratch {
            return Ok(());
        }
        column.sync()
    }
}
