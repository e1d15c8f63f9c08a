//! Input-order buckets for the export: one pass over the tiles writes each
//! point's record into the region of its output window in a scratch file
//! (the ingest's scatter, in reverse), then each window is read back from
//! its region alone. The store is read once and the records twice, whatever
//! the number of windows; a pass over all tiles per window read the whole
//! store once per window (15 times for 10M points in 256 MiB).
//!
//! Record: the point's offset in its window (u32), then its normal (3 x
//! f32), its values (f32 each) and flags byte if the output carries them;
//! little-endian. The
//! coordinates are not carried: the export reads the input's own, in input
//! order. Within a region records land in whatever order the
//! threads flush them; each one names its slot, so the output does not
//! depend on that order.

use super::slots::{Columns, Slots, TileValues};
use super::{PointStore, StoreError, TileEntry};
use crate::io::scratch::ScratchFile;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};

const SCRATCH_FILE: &str = ".export.buckets";
/// Records read back at a time.
const READ_RECORDS: usize = 1 << 16;

/// The scratch file of records sorted into windows, removed on drop.
pub(super) struct Reorder {
    scratch: ScratchFile,
    window: u64,
    count: u64,
    layout: Layout,
}

/// Which fields a record carries.
#[derive(Clone, Copy)]
struct Layout {
    normals: bool,
    /// Values a point (0 when the output carries none).
    values: usize,
    flags: bool,
}

impl Layout {
    fn bytes(&self) -> usize {
        4 + if self.normals { 12 } else { 0 } + 4 * self.values + usize::from(self.flags)
    }
}

impl Reorder {
    /// Writes every point of `store` into the region of its window of
    /// `window` consecutive input ids. Bucket buffers hold about one
    /// window's records in all, split among the threads.
    pub(super) fn build(
        store: &PointStore,
        cols: &Columns,
        window: u64,
    ) -> Result<Self, StoreError> {
        let scratch = ScratchFile::create(store.dir.join(SCRATCH_FILE))?;
        let reorder = Reorder {
            scratch,
            window: window.max(1),
            count: store.len(),
            layout: Layout {
                normals: cols.normals.is_some(),
                values: match cols.values {
                    Some(_) => cols.per_point,
                    None => 0,
                },
                flags: cols.flags.is_some(),
            },
        };
        let windows = reorder.count.div_ceil(reorder.window);
        let cursors: Vec<AtomicU64> = (0..windows)
            .map(|w| AtomicU64::new(w * reorder.window))
            .collect();
        let threads = rayon::current_num_threads().max(1);
        let cap = (reorder.window / windows.max(1) / threads as u64).max(64) as usize;
        let group = store.tiles().len().div_ceil(threads).max(1);
        store
            .tiles()
            .par_chunks(group)
            .try_for_each(|tiles| reorder.scatter(store, cols, tiles, &cursors, cap))?;
        Ok(reorder)
    }

    /// Sorts the records of `tiles` into buckets of `cap` records, flushing
    /// each full bucket to its window's region.
    fn scatter(
        &self,
        store: &PointStore,
        cols: &Columns,
        tiles: &[TileEntry],
        cursors: &[AtomicU64],
        cap: usize,
    ) -> Result<(), StoreError> {
        let rec = self.layout.bytes();
        let mut buckets: Vec<Vec<u8>> = (0..cursors.len()).map(|_| Vec::new()).collect();
        let (mut ids, mut tv) = (Vec::new(), TileValues::default());
        let per = self.layout.values;
        for t in tiles {
            store.read_indices(t.start, t.count, &mut ids)?;
            cols.read(t, &mut tv)?;
            for (k, &id) in ids.iter().enumerate() {
                if id >= self.count {
                    return Err(self.corrupt(format!("input index {id} of {}", self.count)));
                }
                let w = (id / self.window) as usize;
                let b = &mut buckets[w];
                if b.capacity() == 0 {
                    b.reserve_exact(cap * rec);
                }
                b.extend_from_slice(&((id % self.window) as u32).to_le_bytes());
                let (normal, values, flags) = tv.of(k, per);
                if self.layout.normals {
                    normal
                        .iter()
                        .for_each(|v| b.extend_from_slice(&v.to_le_bytes()));
                }
                values
                    .iter()
                    .for_each(|v| b.extend_from_slice(&v.to_le_bytes()));
                if self.layout.flags {
                    b.push(flags);
                }
                if b.len() >= cap * rec {
                    self.flush(w, b, cursors)?;
                }
            }
        }
        for (w, b) in buckets.iter_mut().enumerate() {
            self.flush(w, b, cursors)?;
        }
        Ok(())
    }

    /// Appends bucket `w` to its window's region.
    fn flush(
        &self,
        w: usize,
        bucket: &mut Vec<u8>,
        cursors: &[AtomicU64],
    ) -> Result<(), StoreError> {
        let rec = self.layout.bytes();
        let n = (bucket.len() / rec) as u64;
        if n == 0 {
            return Ok(());
        }
        let at = cursors[w].fetch_add(n, Ordering::Relaxed);
        let end = ((w as u64 + 1) * self.window).min(self.count);
        if at + n > end {
            return Err(self.corrupt(format!("window {w} gets more than its points")));
        }
        self.scratch.write_at(bucket, at * rec as u64)?;
        bucket.clear();
        Ok(())
    }

    /// Fills the slots of one window (starting at a multiple of the window)
    /// from its region, read once: each block of records is placed by all
    /// threads at once, each into the slots of its own id range.
    pub(super) fn fill(&self, slots: Slots) -> Result<(), StoreError> {
        let first = slots.first;
        let len = slots.len as u64;
        if !first.is_multiple_of(self.window) || first + len > self.count {
            return Err(self.corrupt(format!("window at {first} of {len} points")));
        }
        let rec = self.layout.bytes();
        let mut parts = slots.split(rayon::current_num_threads());
        let mut buf = vec![0u8; READ_RECORDS.min(len as usize) * rec];
        let mut done = 0;
        while done < len {
            let n = (len - done).min(READ_RECORDS as u64) as usize;
            self.scratch
                .read_at(&mut buf[..n * rec], (first + done) * rec as u64)?;
            let records = &buf[..n * rec];
            parts
                .par_iter_mut()
                .for_each(|part| self.place(first, records, part));
            done += n as u64;
        }
        Ok(())
    }

    /// Places those of `records` (of the window starting at `first`) whose
    /// slots fall in `part`.
    fn place(&self, first: u64, records: &[u8], part: &mut Slots) {
        let rec = self.layout.bytes();
        let range = part.range();
        let mut normal = [0f32; 3];
        let mut values = vec![0f32; self.layout.values];
        let values_at = if self.layout.normals { 16 } else { 4 };
        for r in records.chunks_exact(rec) {
            let id = first + u64::from(u32::from_le_bytes([r[0], r[1], r[2], r[3]]));
            if !range.contains(&id) {
                continue;
            }
            let f32_at = |o: usize| f32::from_le_bytes([r[o], r[o + 1], r[o + 2], r[o + 3]]);
            if self.layout.normals {
                normal = [f32_at(4), f32_at(8), f32_at(12)];
            }
            for (j, v) in values.iter_mut().enumerate() {
                *v = f32_at(values_at + 4 * j);
            }
            let flags = if self.layout.flags { r[rec - 1] } else { 0 };
            part.place((id - range.start) as usize, &normal, &values, flags);
        }
    }

    fn corrupt(&self, reason: String) -> StoreError {
        StoreError::Corrupt {
            path: self.scratch.path().to_path_buf(),
            reason,
        }
    }
}
