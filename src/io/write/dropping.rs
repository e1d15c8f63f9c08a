//! Rows a flag mask leaves out of an output ([`WriterSpec::drop_flagged`]):
//! `outliers --drop` writes the points the rule keeps, as PCL's and
//! Open3D's filters return them. A wrapper round any writer, so every
//! format (and a LAS input's own records) is left out of alike; the kept
//! rows go on in batches of at most [`BATCH`] points, so the memory it adds
//! does not grow with the export's windows.

use crate::io::{IoError, PointChunk, PointWriter, WriterSpec};
use std::path::PathBuf;

/// Points gathered before they are handed on.
const BATCH: usize = 1 << 16;

pub(super) struct DropFlagged {
    inner: Box<dyn PointWriter>,
    path: PathBuf,
    mask: u8,
    /// Computed values per point.
    per: usize,
    out: PointChunk,
    flags: Vec<u8>,
}

impl DropFlagged {
    /// Wraps `inner`, which writes what `spec` asks but the flagged rows.
    pub(super) fn new(
        inner: Box<dyn PointWriter>,
        path: &std::path::Path,
        spec: &WriterSpec,
    ) -> Self {
        DropFlagged {
            inner,
            path: path.to_path_buf(),
            mask: spec.drop_flagged,
            per: spec.values.len(),
            out: PointChunk::default(),
            flags: Vec::new(),
        }
    }

    /// Appends row `i` of `chunk` to the batch.
    fn push(&mut self, chunk: &PointChunk, i: usize, flag: u8) {
        if self.out.xyz.is_empty() {
            self.out.clear();
            self.out.attrs.reset(chunk.attrs.set());
            self.out.normals = chunk.normals.as_ref().map(|_| Vec::new());
            self.flags.clear();
        }
        self.out.xyz.push(chunk.xyz[i]);
        if let (Some(to), Some(from)) = (&mut self.out.normals, &chunk.normals) {
            to.push(from[i]);
        }
        let per = self.per;
        if let Some(v) = chunk.values.get(per * i..per * (i + 1)) {
            self.out.values.extend_from_slice(v);
        }
        self.out.attrs.push(&chunk.attrs.get(i));
        if let Some(r) = chunk.attrs.las.record(i, chunk.len()) {
            self.out.attrs.las.push(r);
        }
        self.flags.push(flag);
    }

    fn flush(&mut self) -> Result<(), IoError> {
        if self.out.xyz.is_empty() {
            return Ok(());
        }
        self.inner.write_chunk(&self.out, Some(&self.flags))?;
        self.out.xyz.clear();
        Ok(())
    }
}

impl PointWriter for DropFlagged {
    fn write_chunk(&mut self, chunk: &PointChunk, flags: Option<&[u8]>) -> Result<(), IoError> {
        let Some(flags) = flags.filter(|f| f.len() == chunk.len()) else {
            return Err(IoError::Unsupported {
                path: self.path.clone(),
                reason: format!("writer needs {} flags for this chunk", chunk.len()),
            });
        };
        for (i, &flag) in flags.iter().enumerate() {
            if flag & self.mask == 0 {
                self.push(chunk, i, flag);
                if self.out.xyz.len() >= BATCH {
                    self.flush()?;
                }
            }
        }
        Ok(())
    }

    fn finish(mut self: Box<Self>) -> Result<u64, IoError> {
        self.flush()?;
        self.inner.finish()
    }
}
