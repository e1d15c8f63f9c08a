//! XYZ text point writer: `x y z [nx ny nz] [flags]` per line, no header,
//! numbers in shortest round-trip form (see [`encode_text`]).

use super::ply::encode_text;
use super::{check_chunk, open_output};
use crate::io::{AtomicFile, IoError, PointChunk, PointWriter, WriterSpec};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

pub(crate) struct XyzWriter {
    path: PathBuf,
    spec: WriterSpec,
    out: BufWriter<File>,
    atomic: AtomicFile,
    count: u64,
    buf: Vec<u8>,
}

impl XyzWriter {
    pub fn create(path: &Path, spec: &WriterSpec) -> Result<Self, IoError> {
        let (atomic, out) = open_output(path)?;
        Ok(XyzWriter {
            path: path.to_path_buf(),
            spec: spec.clone(),
            out,
            atomic,
            count: 0,
            buf: Vec::new(),
        })
    }
}

impl PointWriter for XyzWriter {
    fn write_chunk(&mut self, chunk: &PointChunk, flags: Option<&[u8]>) -> Result<(), IoError> {
        let c = check_chunk(&self.path, &self.spec, chunk, flags, self.count)?;
        self.buf.clear();
        encode_text(&mut self.buf, chunk, &c, 0..chunk.len());
        self.out
            .write_all(&self.buf)
            .map_err(|e| IoError::os(&self.path, e))?;
        self.count += chunk.len() as u64;
        Ok(())
    }

    fn finish(self: Box<Self>) -> Result<u64, IoError> {
        let XyzWriter {
            path,
            spec,
            out,
            atomic,
            count,
            ..
        } = *self;
        super::check_count(&path, &spec, count)?;
        out.into_inner()
            .map_err(|e| IoError::os(&path, e.into_error()))?;
        atomic.commit()?;
        Ok(count)
    }
}
