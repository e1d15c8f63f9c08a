//! Per-point records in input order, for outputs whose fields the store's
//! point export does not carry (the curvature). Tiles are in spatial order,
//! the output in input order: each tile's records are sorted into the
//! regions of their output windows in a scratch file (a bucket per window,
//! flushed when full), then each window is read back, placed by slot and
//! written. The store is read once and the records twice, whatever the
//! number of windows; memory is one window plus the buckets (about one
//! window in all). The same scheme as `store::reorder`, over opaque records.

use crate::io::scratch::ScratchFile;
use crate::store::{PointStore, StoreError, TileEntry};

const SCRATCH_FILE: &str = ".features.order";

/// Hands one record of `record` bytes per point of `store` to `emit`, in
/// input order, a window at a time: `emit(first, records)` gets the
/// records of input ids `first..` (whole records). `fill(tile, ids, buf)`
/// appends the records of a tile's points in store order (`ids` their
/// input indices). `window` is the number of records held in memory at
/// once.
pub fn write_in_input_order(
    store: &PointStore,
    record: usize,
    window: u64,
    mut emit: impl FnMut(u64, &[u8]) -> Result<(), StoreError>,
    mut fill: impl FnMut(&TileEntry, &[u64], &mut Vec<u8>) -> Result<(), StoreError>,
) -> Result<(), StoreError> {
    let n = store.len();
    let window = window.clamp(1, n.max(1));
    let windows = n.div_ceil(window) as usize;
    let slot_rec = record + 4;
    let path = store.dir().join(SCRATCH_FILE);
    let scratch = ScratchFile::create(path.clone())?;
    let mut cursors: Vec<u64> = (0..windows as u64).map(|w| w * window).collect();
    let cap = ((window / windows.max(1) as u64).max(256) as usize) * slot_rec;
    let mut buckets: Vec<Vec<u8>> = vec![Vec::new(); windows];
    let (mut ids, mut recs) = (Vec::new(), Vec::new());
    for t in store.tiles() {
        store.read_indices(t.start, t.count, &mut ids)?;
        recs.clear();
        fill(t, &ids, &mut recs)?;
        if recs.len() != ids.len() * record {
            return Err(corrupt(&path, "a tile's records do not match its points"));
        }
        for (&id, r) in ids.iter().zip(recs.chunks_exact(record)) {
            if id >= n {
                return Err(corrupt(&path, &format!("input index {id} of {n}")));
            }
            let w = (id / window) as usize;
            let b = &mut buckets[w];
            b.extend_from_slice(&((id % window) as u32).to_le_bytes());
            b.extend_from_slice(r);
            if b.len() >= cap {
                flush(
                    &scratch,
                    b,
                    &mut cursors[w],
                    slot_rec,
                    region_end(w, window, n),
                )?;
            }
        }
    }
    for (w, (b, c)) in buckets.iter_mut().zip(cursors.iter_mut()).enumerate() {
        flush(&scratch, b, c, slot_rec, region_end(w, window, n))?;
    }
    drop(buckets);
    let mut placed = Vec::new();
    let mut raw = Vec::new();
    for w in 0..windows as u64 {
        let first = w * window;
        let len = (n - first).min(window) as usize;
        if cursors[w as usize] != first + len as u64 {
            return Err(corrupt(&path, "a window did not get all its points"));
        }
        raw.resize(len * slot_rec, 0);
        scratch.read_at(&mut raw, first * slot_rec as u64)?;
        placed.clear();
        placed.resize(len * record, 0);
        for r in raw.chunks_exact(slot_rec) {
            let slot = u32::from_le_bytes([r[0], r[1], r[2], r[3]]) as usize;
            placed[slot * record..(slot + 1) * record].copy_from_slice(&r[4..]);
        }
        emit(first, &placed)?;
    }
    Ok(())
}

fn region_end(w: usize, window: u64, n: u64) -> u64 {
    ((w as u64 + 1) * window).min(n)
}

/// Appends a bucket to its window's region, which must not overflow (a
/// repeated input index would).
fn flush(
    scratch: &ScratchFile,
    bucket: &mut Vec<u8>,
    cursor: &mut u64,
    slot_rec: usize,
    end: u64,
) -> Result<(), StoreError> {
    let count = (bucket.len() / slot_rec) as u64;
    if *cursor + count > end {
        return Err(corrupt(&scratch.path, "a window gets more than its points"));
    }
    if count > 0 {
        scratch.write_at(bucket, *cursor * slot_rec as u64)?;
        *cursor += count;
        bucket.clear();
    }
    Ok(())
}

fn corrupt(path: &std::path::Path, reason: &str) -> StoreError {
    StoreError::Corrupt {
        path: path.to_path_buf(),
        reason: reason.to_string(),
    }
}
