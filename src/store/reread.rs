//! The input read again for an export, when its store keeps nothing of it
//! ([`Kept::Nothing`]): a store built for one run need not hold a copy of
//! the input's coordinates, attributes and records (66 of the 114 scratch
//! bytes a point of a LAS 1.4 input's normals) while the input itself is on
//! disk. The export costs one more read of the input, decoded on a thread
//! of its own while the windows are filled and written.
//!
//! The reader is opened with the build's read options (selection, invalid
//! records, scans), so it yields the same points in the same order. Each
//! is checked: its exact coordinates, encoded as the build encoded them
//! (`super::exact`), hash per segment of `INPUT_SEGMENT` points to the
//! checksums the build kept of `xyz.input` before removing it, and the
//! input must end where the store does. An input changed, replaced or cut
//! during the run fails the export, so no output is renamed into place
//! with other points' attributes beside these normals.

use super::exact::Coordinates;
use super::integrity::INPUT_SEGMENT;
use super::{Kept, PointStore, StoreError};
use crate::io::{open_reader, IoError, PointChunk, PointReader, ReadOptions, DEFAULT_CHUNK};
use crossbeam::channel::{bounded, Receiver, Sender};
use std::path::{Path, PathBuf};
use std::thread::JoinHandle;

/// The input, read again in input order and checked as it goes.
pub(super) struct Reread {
    path: PathBuf,
    ahead: Ahead,
    /// The chunk being handed out, and the next of its points.
    chunk: PointChunk,
    pos: usize,
    /// A LAS input's record length, as the store was built.
    record_len: Option<usize>,
    check: Fingerprint,
}

impl Reread {
    /// `input`, the file `store` was built from, read as `read` says.
    pub(super) fn open(
        store: &PointStore,
        input: &Path,
        read: &ReadOptions,
    ) -> Result<Self, StoreError> {
        debug_assert_eq!(store.kept(), Kept::Nothing);
        let reader = open_reader(input, read.clone())?;
        Ok(Reread {
            path: input.to_path_buf(),
            ahead: Ahead::start(reader),
            chunk: PointChunk::default(),
            pos: 0,
            record_len: store.manifest.las.map(|l| usize::from(l.record_len)),
            check: Fingerprint {
                coordinates: store.coordinates(),
                sums: store.manifest.input_sums.clone(),
                count: store.len(),
                hasher: crc32fast::Hasher::new(),
                hashed: 0,
                bytes: Vec::new(),
            },
        })
    }

    /// Appends the next `len` points to `out`: their coordinates, the
    /// attributes of `out.attrs`' set and, when `records`, their LAS
    /// records.
    pub(super) fn next(
        &mut self,
        len: usize,
        out: &mut PointChunk,
        records: bool,
    ) -> Result<(), StoreError> {
        let mut left = len;
        while left > 0 {
            if self.pos == self.chunk.len() {
                self.pos = 0;
                self.chunk = self.ahead.next(std::mem::take(&mut self.chunk))?;
                if self.chunk.is_empty() {
                    return Err(self.changed(format!(
                        "it ends after {} points, the store holds {}",
                        self.check.hashed, self.check.count
                    )));
                }
            }
            let record_len = self.chunk.attrs.las.record_len;
            if records && Some(record_len) != self.record_len {
                return Err(self.changed(format!(
                    "its LAS records are {record_len} bytes, {} when it was read",
                    self.record_len.unwrap_or(0)
                )));
            }
            let take = left.min(self.chunk.len() - self.pos);
            let range = self.pos..self.pos + take;
            if let Some(k) = self.check.add(&self.chunk.xyz[range.clone()]) {
                return Err(self.changed(k));
            }
            out.xyz.extend_from_slice(&self.chunk.xyz[range.clone()]);
            out.attrs
                .extend_from(&self.chunk.attrs, range.clone(), records);
            self.pos += take;
            left -= take;
        }
        Ok(())
    }

    /// Checks that the input ends where the store does.
    pub(super) fn finish(mut self) -> Result<(), StoreError> {
        let more =
            self.chunk.len() - self.pos + self.ahead.next(std::mem::take(&mut self.chunk))?.len();
        if more > 0 || self.check.hashed != self.check.count {
            return Err(self.changed(format!(
                "it holds more than the store's {} points",
                self.check.count
            )));
        }
        Ok(())
    }

    fn changed(&self, what: String) -> StoreError {
        StoreError::InputChanged {
            path: self.path.clone(),
            what,
        }
    }
}

/// The build's checksums of the exact coordinates, recomputed over the
/// points read again.
struct Fingerprint {
    coordinates: Coordinates,
    sums: Vec<u32>,
    count: u64,
    hasher: crc32fast::Hasher,
    /// Points hashed so far.
    hashed: u64,
    bytes: Vec<u8>,
}

impl Fingerprint {
    /// Hashes the next points; says which differ when a segment ends on
    /// a checksum other than the build's.
    fn add(&mut self, pts: &[glam::DVec3]) -> Option<String> {
        let mut rest = pts;
        while !rest.is_empty() {
            let in_segment = INPUT_SEGMENT - self.hashed % INPUT_SEGMENT;
            let end = self.count.min(self.hashed + in_segment);
            let n = rest.len().min((end.saturating_sub(self.hashed)) as usize);
            if n == 0 {
                return Some(format!(
                    "it holds more than the store's {} points",
                    self.count
                ));
            }
            let (now, later) = rest.split_at(n);
            self.bytes.clear();
            if now
                .iter()
                .any(|p| self.coordinates.encode(*p, &mut self.bytes).is_none())
            {
                return Some(self.segment_text(self.hashed / INPUT_SEGMENT));
            }
            self.hasher.update(&self.bytes);
            self.hashed += n as u64;
            if self.hashed == end {
                let sum = std::mem::replace(&mut self.hasher, crc32fast::Hasher::new()).finalize();
                let k = (self.hashed - 1) / INPUT_SEGMENT;
                if self.sums.get(k as usize) != Some(&sum) {
                    return Some(self.segment_text(k));
                }
            }
            rest = later;
        }
        None
    }

    /// Segment `k`, in words.
    fn segment_text(&self, k: u64) -> String {
        let start = k * INPUT_SEGMENT;
        let end = (start + INPUT_SEGMENT).min(self.count);
        format!("points {start}..{end}")
    }
}

/// A reader decoding on a thread of its own, a chunk ahead of its
/// consumer: a compressed input's decoding is most of a read, and it
/// overlaps the export's placing and writing.
struct Ahead {
    full: Option<Receiver<Result<PointChunk, IoError>>>,
    empty: Option<Sender<PointChunk>>,
    thread: Option<JoinHandle<()>>,
}

impl Ahead {
    fn start(mut reader: Box<dyn PointReader>) -> Self {
        let (full_tx, full_rx) = bounded::<Result<PointChunk, IoError>>(1);
        let (empty_tx, empty_rx) = bounded::<PointChunk>(2);
        let _ = empty_tx.send(PointChunk::default());
        let thread = std::thread::spawn(move || {
            // Ends when the consumer hangs up or the input does.
            while let Ok(mut chunk) = empty_rx.recv() {
                let read = reader.read_chunk(&mut chunk, DEFAULT_CHUNK);
                let last = !matches!(read, Ok(n) if n > 0);
                if full_tx.send(read.map(|_| chunk)).is_err() || last {
                    break;
                }
            }
        });
        Ahead {
            full: Some(full_rx),
            empty: Some(empty_tx),
            thread: Some(thread),
        }
    }

    /// The next chunk (empty at the input's end), handing `used` back to
    /// be filled.
    fn next(&mut self, used: PointChunk) -> Result<PointChunk, StoreError> {
        if let Some(empty) = &self.empty {
            let _ = empty.send(used);
        }
        match self.full.as_ref().map(|f| f.recv()) {
            Some(Ok(read)) => Ok(read?),
            // The reader ended (its last chunk was empty or an error).
            _ => Ok(PointChunk::default()),
        }
    }
}

impl Drop for Ahead {
    fn drop(&mut self) {
        // Hang up first, so a reader waiting to send or receive ends.
        self.full.take();
        self.empty.take();
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}
