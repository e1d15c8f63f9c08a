//! Per-point outputs that keep the points a selection left out
//! (`--unselected keep`): every input record that holds a point gets its
//! row, in input order, the unselected ones with the input's coordinates
//! and attributes, a NaN normal and the flag [`UNSELECTED`].
//!
//! The processed points reach the writer in input order (the export's
//! windows, a conversion's chunks) without their record numbers: a store
//! holds the selected points only. [`KeepUnselected`] reads the input a
//! second time, every point, beside them, and decides with the same
//! selection which records were processed: the next processed row is
//! the next selected record, so the unselected records between two of
//! them are written in between. Memory is a chunk of the input and a
//! batch of rows; the cost is one more read of the input.

use super::select::Selector;
use super::{
    open_reader, AttributeSet, AttributeValues, IoError, PointChunk, PointReader, PointWriter,
    ReadOptions, Selection, WriterSpec, DEFAULT_CHUNK,
};
use glam::{DVec3, Vec3};
use std::path::{Path, PathBuf};

/// What a per-point output holds of the points a selection leaves out
/// (the CLI's `--unselected`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Unselected {
    /// Per-point outputs hold the selected points only.
    #[default]
    Drop,
    /// Per-point outputs hold every input point, the unselected flagged.
    Keep,
}

/// The flag of a row a selection left out, with `--unselected keep`, in
/// every per-point output: nothing was computed for it (NaN values).
pub const UNSELECTED: u8 = 128;

/// Rows gathered before they are handed to the writer.
const BATCH: usize = 1 << 14;

/// The input read again, every point, to find the unselected points
/// between two processed (selected) ones.
pub struct UnselectedRows {
    input: Box<dyn PointReader>,
    selector: Selector,
    current: PointChunk,
    pos: usize,
    kept: u64,
}

impl UnselectedRows {
    /// `input` read with `read`'s policy, its points judged by `read`'s
    /// selection.
    pub fn open(input: &Path, read: &ReadOptions) -> Result<Self, IoError> {
        let every = ReadOptions {
            select: Selection::default(),
            ..read.clone()
        };
        Ok(UnselectedRows {
            input: open_reader(input, every)?,
            selector: Selector::new(&read.select),
            current: PointChunk::default(),
            pos: 0,
            kept: 0,
        })
    }

    /// Unselected points handed out so far.
    pub fn kept(&self) -> u64 {
        self.kept
    }

    /// The input's next point, or `None` at its end.
    fn next_record(&mut self) -> Result<Option<usize>, IoError> {
        if self.pos == self.current.len() {
            self.pos = 0;
            if self.input.read_chunk(&mut self.current, DEFAULT_CHUNK)? == 0 {
                return Ok(None);
            }
        }
        self.pos += 1;
        Ok(Some(self.pos - 1))
    }

    /// Calls `f` with each unselected point (position, attributes, and its
    /// LAS record when the input is LAS) up to
    /// the input's next selected one, which it passes over; `false` when
    /// the input ended first.
    pub fn up_to_selected<E: From<IoError>>(
        &mut self,
        mut f: impl FnMut(DVec3, &AttributeValues, Option<&[u8]>) -> Result<(), E>,
    ) -> Result<bool, E> {
        while let Some(i) = self.next_record()? {
            if self.selector.selects(&self.current, i) {
                return Ok(true);
            }
            self.kept += 1;
            let c = &self.current;
            f(c.xyz[i], &c.attrs.get(i), c.attrs.las.record(i, c.len()))?;
        }
        Ok(false)
    }
}

/// A row's computed fields: its normal, values and flag.
struct Row<'a> {
    normal: Vec3,
    values: &'a [f32],
    flag: u8,
}

/// A writer of processed points that writes the unselected points of
/// the input between them.
pub struct KeepUnselected {
    inner: Box<dyn PointWriter>,
    path: PathBuf,
    rows: Option<UnselectedRows>,
    with_normals: bool,
    with_flags: bool,
    /// Computed values per point (NaN for an unselected row).
    values: usize,
    attributes: AttributeSet,
    out: PointChunk,
    out_flags: Vec<u8>,
}

impl KeepUnselected {
    /// Wraps `inner`, which writes `output` as `spec` asks, so that the
    /// points of `input` (read with `read`'s policy) that `read`'s
    /// selection leaves out are written too.
    pub fn wrap(
        inner: Box<dyn PointWriter>,
        output: &Path,
        input: &Path,
        read: &ReadOptions,
        spec: &WriterSpec,
    ) -> Result<Self, IoError> {
        Ok(KeepUnselected {
            inner,
            path: output.to_path_buf(),
            rows: Some(UnselectedRows::open(input, read)?),
            with_normals: spec.with_normals,
            with_flags: spec.with_flags,
            values: spec.values.len(),
            attributes: spec.attributes,
            out: PointChunk::default(),
            out_flags: Vec::new(),
        })
    }

    /// Writes the input's unselected points up to its next selected one;
    /// `false` when the input ended first.
    fn up_to_selected(&mut self) -> Result<bool, IoError> {
        let Some(mut rows) = self.rows.take() else {
            return Ok(false);
        };
        let none = [f32::NAN].repeat(self.values);
        let more = rows.up_to_selected(|p, a, r| {
            let row = Row {
                normal: Vec3::NAN,
                values: &none,
                flag: UNSELECTED,
            };
            self.push(p, a, r, row)
        });
        self.rows = Some(rows);
        more
    }

    fn push(
        &mut self,
        p: DVec3,
        a: &AttributeValues,
        record: Option<&[u8]>,
        row: Row,
    ) -> Result<(), IoError> {
        if self.out.xyz.is_empty() {
            self.out.clear();
            self.out.attrs.reset(self.attributes);
            self.out.normals = self.with_normals.then(Vec::new);
            self.out_flags.clear();
        }
        self.out.xyz.push(p);
        if let Some(n) = &mut self.out.normals {
            n.push(row.normal);
        }
        self.out.values.extend_from_slice(row.values);
        let flag = row.flag;
        self.out.attrs.push(a);
        if let Some(r) = record {
            self.out.attrs.las.push(r);
        }
        if self.with_flags {
            self.out_flags.push(flag);
        }
        if self.out.xyz.len() >= BATCH {
            self.flush()?;
        }
        Ok(())
    }

    fn flush(&mut self) -> Result<(), IoError> {
        if self.out.xyz.is_empty() {
            return Ok(());
        }
        let flags = self.with_flags.then_some(self.out_flags.as_slice());
        self.inner.write_chunk(&self.out, flags)?;
        self.out.xyz.clear();
        Ok(())
    }

    fn short(&self) -> IoError {
        IoError::Unsupported {
            path: self.path.clone(),
            reason: "more points to write than the input holds selected points: the input changed during the run".into(),
        }
    }
}

impl PointWriter for KeepUnselected {
    fn write_chunk(&mut self, chunk: &PointChunk, flags: Option<&[u8]>) -> Result<(), IoError> {
        for i in 0..chunk.len() {
            if !self.up_to_selected()? {
                return Err(self.short());
            }
            let per = self.values;
            let row = Row {
                normal: chunk.normals.as_ref().map_or(Vec3::ZERO, |n| n[i]),
                values: chunk.values.get(per * i..per * (i + 1)).unwrap_or(&[]),
                flag: flags.map_or(0, |f| f[i]),
            };
            let record = chunk.attrs.las.record(i, chunk.len());
            self.push(chunk.xyz[i], &chunk.attrs.get(i), record, row)?;
        }
        Ok(())
    }

    fn finish(mut self: Box<Self>) -> Result<u64, IoError> {
        if self.up_to_selected()? {
            return Err(IoError::Unsupported {
                path: self.path.clone(),
                reason: "fewer points written than the input holds selected points".into(),
            });
        }
        self.flush()?;
        self.inner.finish()
    }
}
