//! The store's attribute columns (intensity, colour, classification, return
//! number, GPS time): one file per attribute the input carries, written
//! during the first read of the input and kept in *input* order, unlike the
//! tile-sorted coordinates. No kernel reads them; only the export does, and
//! it writes in input order, so a window of output is one sequential read
//! of each column and the build never sorts or scatters them.

use super::las_kept::RecordSink;
use super::{Column, PointStore, StoreError};
use crate::io::{Attribute, AttributeMaxima, AttributeSet, Attributes, PointChunk};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// File name of attribute `a`'s column.
pub fn column_file(a: Attribute) -> String {
    format!("{}.input", a.name())
}

/// Writes the attribute columns (and a LAS input's records) as the
/// input's chunks arrive, and finds the largest values.
pub(super) struct AttributeSink {
    columns: Vec<(Attribute, PathBuf, BufWriter<File>)>,
    records: Option<RecordSink>,
    maxima: AttributeMaxima,
    bytes: Vec<u8>,
}

impl AttributeSink {
    /// Columns for `set`, and for a LAS input's records of `las_record`
    /// bytes.
    pub fn create(
        dir: &Path,
        set: AttributeSet,
        las_record: Option<u16>,
    ) -> Result<Self, StoreError> {
        let mut columns = Vec::new();
        for a in set.iter() {
            let path = dir.join(column_file(a));
            let file = File::create(&path).map_err(|e| StoreError::os(&path, e))?;
            columns.push((a, path, BufWriter::with_capacity(1 << 16, file)));
        }
        let records = match las_record {
            Some(len) => Some(RecordSink::create(dir, len)?),
            None => None,
        };
        Ok(AttributeSink {
            columns,
            records,
            maxima: AttributeMaxima::default(),
            bytes: Vec::new(),
        })
    }

    /// Appends the chunk's values (its points are the next in input order).
    pub fn write(&mut self, chunk: &PointChunk) -> Result<(), StoreError> {
        self.maxima.add(&chunk.attrs);
        if let Some(r) = &mut self.records {
            r.write(chunk)?;
        }
        for (a, path, out) in &mut self.columns {
            self.bytes.clear();
            chunk.attrs.encode_le(*a, &mut self.bytes);
            if self.bytes.len() != chunk.len() * a.item_bytes() {
                return Err(StoreError::Corrupt {
                    path: path.clone(),
                    reason: format!("the reader gave no {} for some points", a.name()),
                });
            }
            out.write_all(&self.bytes)
                .map_err(|e| StoreError::os(path.as_path(), e))?;
        }
        Ok(())
    }

    /// Flushes the columns; returns the largest values.
    pub fn finish(self) -> Result<AttributeMaxima, StoreError> {
        for (_, path, out) in self.columns {
            out.into_inner()
                .map_err(|e| StoreError::os(&path, e.into_error()))?;
        }
        if let Some(r) = self.records {
            r.finish()?;
        }
        Ok(self.maxima)
    }
}

impl PointStore {
    /// The attributes the store keeps for its points.
    pub fn attributes(&self) -> AttributeSet {
        AttributeSet::of(&self.manifest.attributes)
    }

    /// Values of the attributes `set` (a subset of [`PointStore::attributes`])
    /// for the points of input-order ranks `[first, first + count)`, into
    /// `out`.
    pub fn read_attributes(
        &self,
        first: u64,
        count: u64,
        set: AttributeSet,
        out: &mut Attributes,
    ) -> Result<(), StoreError> {
        out.reset(set);
        for a in set.iter() {
            let col = self.attribute_column(a)?;
            col.with_bytes(first, count, |b| out.decode_le(a, b))?;
        }
        Ok(())
    }

    fn attribute_column(&self, a: Attribute) -> Result<Column, StoreError> {
        self.keeps_input(true)?;
        if !self.attributes().contains(a) {
            return Err(StoreError::MissingColumn {
                column: super::ColumnName::Attribute(a),
            });
        }
        Column::open(&self.dir.join(column_file(a)), a.item_bytes(), false)
    }

    /// Checks that every attribute column holds a value per point.
    pub(super) fn check_attribute_columns(&self) -> Result<(), StoreError> {
        if self.kept() != super::Kept::All {
            return Ok(());
        }
        for a in self.attributes().iter() {
            let col = self.attribute_column(a)?;
            if col.items()? != self.manifest.count {
                return Err(StoreError::Corrupt {
                    path: col.path().to_path_buf(),
                    reason: format!(
                        "holds {} values, the store has {} points",
                        col.items()?,
                        self.manifest.count
                    ),
                });
            }
        }
        Ok(())
    }
}
