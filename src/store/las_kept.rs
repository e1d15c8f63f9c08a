//! What a store keeps of a LAS/LAZ input so that a LAS output of it is
//! written as the input came: its point records byte for byte, in input
//! order (`las.input`, the input's record length a point: every standard
//! field and the extra bytes, decompressed), the input's bytes before its
//! points (`las.head`: header, VLRs, padding) and its bytes from the first
//! EVLR or waveform record on (`las.tail`). The input may be gone or
//! changed by the time the output is written (a run resumed later), so
//! the store holds copies, not the input's path. The records column is
//! checksummed like every input-order column; the head and tail by a
//! CRC-32 each in the manifest, checked when they are read back.

use super::{Column, PointStore, StoreError};
use crate::io::{IoError, LasRecords, LasSource, PointChunk};
use serde::{Deserialize, Serialize};
use std::fs::File;
use std::io::{BufWriter, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

/// The input's point records, input order.
pub(crate) const LAS_RECORDS_FILE: &str = "las.input";
const LAS_HEAD_FILE: &str = "las.head";
const LAS_TAIL_FILE: &str = "las.tail";

/// The manifest's note of a kept LAS input.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq)]
pub struct LasKept {
    /// Bytes of one point record.
    pub record_len: u16,
    /// CRC-32 of `las.head`.
    pub head_crc32: u32,
    /// CRC-32 of `las.tail`, absent when the input has no EVLR.
    pub tail_crc32: Option<u32>,
}

/// Copies `input`'s head and tail into the store at `dir`; returns the
/// manifest's note (its record length and the copies' checksums).
pub(super) fn keep_frame(dir: &Path, input: &Path) -> Result<LasKept, StoreError> {
    let source = LasSource::read(input)?;
    let head = dir.join(LAS_HEAD_FILE);
    std::fs::write(&head, source.head()).map_err(|e| StoreError::os(&head, e))?;
    let tail = dir.join(LAS_TAIL_FILE);
    let tail_crc32 = match crate::io::las_file::tail_start(&source.header) {
        Some(start) => Some(copy_tail(input, start, &tail)?),
        None => None,
    };
    Ok(LasKept {
        record_len: source.record_len(),
        head_crc32: crc32fast::hash(source.head()),
        tail_crc32,
    })
}

/// Copies `input` from byte `start` on to `to` (waveform packets can be
/// large: through a buffer, hashed as they pass); returns the CRC-32.
fn copy_tail(input: &Path, start: u64, to: &Path) -> Result<u32, StoreError> {
    let os = |e| StoreError::Input(IoError::os(input, e));
    let mut f = File::open(input).map_err(os)?;
    f.seek(SeekFrom::Start(start)).map_err(os)?;
    let out = File::create(to).map_err(|e| StoreError::os(to, e))?;
    let mut out = BufWriter::with_capacity(1 << 16, out);
    let mut hasher = crc32fast::Hasher::new();
    let mut buf = vec![0u8; 1 << 16];
    loop {
        let n = f.read(&mut buf).map_err(os)?;
        if n == 0 {
            break;
        }
        hasher.update(&buf[..n]);
        out.write_all(&buf[..n])
            .map_err(|e| StoreError::os(to, e))?;
    }
    out.into_inner()
        .map_err(|e| StoreError::os(to, e.into_error()))?;
    Ok(hasher.finalize())
}

/// CRC-32 of the file at `path`.
fn file_crc32(path: &Path) -> Result<u32, StoreError> {
    let mut hasher = crc32fast::Hasher::new();
    let mut f = File::open(path).map_err(|e| StoreError::os(path, e))?;
    let mut buf = vec![0u8; 1 << 16];
    loop {
        let n = f.read(&mut buf).map_err(|e| StoreError::os(path, e))?;
        if n == 0 {
            return Ok(hasher.finalize());
        }
        hasher.update(&buf[..n]);
    }
}

/// Appends the input's records to `las.input` as its chunks arrive.
pub(super) struct RecordSink {
    path: PathBuf,
    record_len: usize,
    out: BufWriter<File>,
}

impl RecordSink {
    pub fn create(dir: &Path, record_len: u16) -> Result<Self, StoreError> {
        let path = dir.join(LAS_RECORDS_FILE);
        let file = File::create(&path).map_err(|e| StoreError::os(&path, e))?;
        Ok(RecordSink {
            out: BufWriter::with_capacity(1 << 16, file),
            path,
            record_len: usize::from(record_len),
        })
    }

    /// Appends the chunk's records (its points are the next in input order).
    pub fn write(&mut self, chunk: &PointChunk) -> Result<(), StoreError> {
        let las = &chunk.attrs.las;
        if las.record_len != self.record_len || las.bytes.len() != chunk.len() * self.record_len {
            return Err(StoreError::Corrupt {
                path: self.path.clone(),
                reason: format!(
                    "the reader gave {} bytes of LAS records of {} for {} points of {} bytes",
                    las.bytes.len(),
                    las.record_len,
                    chunk.len(),
                    self.record_len
                ),
            });
        }
        self.out
            .write_all(&las.bytes)
            .map_err(|e| StoreError::os(&self.path, e))
    }

    pub fn finish(self) -> Result<(), StoreError> {
        let path = self.path;
        self.out
            .into_inner()
            .map_err(|e| StoreError::os(&path, e.into_error()))?;
        Ok(())
    }
}

impl PointStore {
    /// The LAS input's frame (header, VLRs, EVLRs) the store keeps, when
    /// it was built from a LAS/LAZ file.
    pub fn las_source(&self) -> Result<Option<LasSource>, StoreError> {
        if self.manifest.las.is_none() {
            return Ok(None);
        }
        let (head, tail) = (self.dir.join(LAS_HEAD_FILE), self.dir.join(LAS_TAIL_FILE));
        Ok(Some(LasSource::from_parts(&head, &tail)?))
    }

    /// Checks the kept LAS head and tail against their checksums (the
    /// records column is checked with the other columns).
    pub(super) fn check_las_frame(&self) -> Result<(), StoreError> {
        let Some(kept) = self.manifest.las else {
            return Ok(());
        };
        let files = [
            (LAS_HEAD_FILE, Some(kept.head_crc32)),
            (LAS_TAIL_FILE, kept.tail_crc32),
        ];
        for (name, crc) in files {
            let Some(crc) = crc else { continue };
            let path = self.dir.join(name);
            if file_crc32(&path)? != crc {
                return Err(StoreError::Damaged {
                    path,
                    what: super::DamagedPart::LasHeader,
                });
            }
        }
        Ok(())
    }

    /// The LAS input's records of the points of input-order ranks
    /// `[first, first + count)`, into `out` (emptied when the store keeps
    /// none).
    pub fn read_las_records(
        &self,
        first: u64,
        count: u64,
        out: &mut LasRecords,
    ) -> Result<(), StoreError> {
        out.bytes.clear();
        let Some(kept) = self.manifest.las else {
            out.record_len = 0;
            return Ok(());
        };
        out.record_len = usize::from(kept.record_len);
        self.keeps_input(true)?;
        let col = Column::open(&self.dir.join(LAS_RECORDS_FILE), out.record_len, false)?;
        col.with_bytes(first, count, |b| out.bytes.extend_from_slice(b))
    }
}
