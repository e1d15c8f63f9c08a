//! Checksums of a store: a CRC-32 per tile of every tile-ordered column,
//! per tile of the block table, per segment of `INPUT_SEGMENT` (2^20) points of
//! every input-order column, and one of the manifest itself. They are
//! written when a column is made (`PointStore::seal_column`) and checked
//! whenever a store is opened ([`PointStore::verify`]), so a store changed
//! behind scanmesh's back (a flipped byte, a column copied from another
//! store, an edited manifest) is refused, naming the column and the tile,
//! instead of being read as data: 64 flipped bytes once turned 149,994 of
//! 150,000 normals. CRC-32 (hardware-assisted, `crc32fast`) runs at memory
//! speed, so the check costs a read of the store, which the run that opens
//! it makes anyway.

use super::manifest::Manifest;
use super::{Column, DamagedPart, PointStore, StoreError, TileEntry, BLOCK, BLOCKS_FILE};
use rayon::prelude::*;
use std::ops::Range;

/// Points per checksum of an input-order column (`*.input`).
pub(crate) const INPUT_SEGMENT: u64 = 1 << 20;

/// How a column's items divide into checksummed segments.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Layout {
    /// One segment per tile, over its store range.
    Tiles,
    /// One segment per tile, over its blocks.
    Blocks,
    /// Segments of [`INPUT_SEGMENT`] points in input order.
    Input,
}

fn layout_of(name: &str) -> Layout {
    match name {
        BLOCKS_FILE => Layout::Blocks,
        n if n.ends_with(".input") => Layout::Input,
        _ => Layout::Tiles,
    }
}

/// Item ranges of the segments of a column laid out as `layout`.
fn segments(layout: Layout, tiles: &[TileEntry], count: u64) -> Vec<Range<u64>> {
    match layout {
        // Saturating: a damaged manifest must fail a check, not overflow.
        Layout::Tiles => tiles
            .iter()
            .map(|t| t.start..t.start.saturating_add(t.count))
            .collect(),
        Layout::Blocks => tiles
            .iter()
            .map(|t| t.first_block..t.first_block.saturating_add(t.count.div_ceil(BLOCK)))
            .collect(),
        Layout::Input => (0..count.div_ceil(INPUT_SEGMENT))
            .map(|s| s * INPUT_SEGMENT..((s + 1) * INPUT_SEGMENT).min(count))
            .collect(),
    }
}

/// What a segment is, in words, for an error.
fn describe(layout: Layout, segment: usize, range: &Range<u64>) -> DamagedPart {
    match layout {
        Layout::Tiles | Layout::Blocks => DamagedPart::Tile(segment),
        Layout::Input => DamagedPart::InputPoints {
            start: range.start,
            end: range.end,
        },
    }
}

/// Bytes mapped at a time while a segment is hashed: a map's touched pages
/// count in RSS until it is dropped, and a segment can be a tile of
/// millions of points.
const MAP_BYTES: u64 = 1 << 20;

/// The CRC-32 of each segment of `column` (`item_bytes` per item).
fn sums_of(
    column: &Column,
    item_bytes: usize,
    ranges: &[Range<u64>],
) -> Result<Vec<u32>, StoreError> {
    let step = (MAP_BYTES / item_bytes.max(1) as u64).max(1);
    ranges
        .par_iter()
        .map(|r| {
            let mut h = crc32fast::Hasher::new();
            let mut at = r.start;
            while at < r.end {
                let n = (r.end - at).min(step);
                column.with_bytes(at, n, |b| h.update(b))?;
                at += n;
            }
            Ok(h.finalize())
        })
        .collect()
}

impl PointStore {
    /// Records the checksums of the column file `name` (`item_bytes` per
    /// item) as it is now; the caller saves the manifest.
    pub(crate) fn seal_column(&mut self, name: &str, item_bytes: usize) -> Result<(), StoreError> {
        let sums = sums_in(&self.dir, &self.manifest, name, item_bytes)?;
        self.manifest.checksums.insert(name.to_string(), sums);
        Ok(())
    }

    /// Checks every column the manifest has checksums of: a segment whose
    /// bytes changed since it was sealed is an error naming the column and
    /// the tile (or input range).
    pub fn verify(&self) -> Result<(), StoreError> {
        for (name, sums) in &self.manifest.checksums {
            let layout = layout_of(name);
            let ranges = segments(layout, &self.manifest.tiles, self.manifest.count);
            let path = self.dir.join(name);
            if ranges.len() != sums.len() {
                return Err(StoreError::Damaged {
                    path,
                    what: DamagedPart::SegmentCount {
                        sums: sums.len(),
                        segments: ranges.len(),
                    },
                });
            }
            let items = ranges.last().map_or(0, |r| r.end);
            let bytes = item_bytes(&path, items)?;
            let now = sums_of(&Column::open(&path, bytes, false)?, bytes, &ranges)?;
            if let Some(k) = (0..sums.len()).find(|&k| now[k] != sums[k]) {
                return Err(StoreError::Damaged {
                    path,
                    what: describe(layout, k, &ranges[k]),
                });
            }
        }
        Ok(())
    }
}

/// Checksums of the column `name` of the store at `dir` described by
/// `manifest`.
pub(super) fn sums_in(
    dir: &std::path::Path,
    manifest: &Manifest,
    name: &str,
    item_bytes: usize,
) -> Result<Vec<u32>, StoreError> {
    let ranges = segments(layout_of(name), &manifest.tiles, manifest.count);
    sums_of(
        &Column::open(&dir.join(name), item_bytes, false)?,
        item_bytes,
        &ranges,
    )
}

/// Bytes per item of the column at `path` whose segments end at item
/// `items`: every column holds whole items, so a length that does not
/// divide is damage too.
fn item_bytes(path: &std::path::Path, items: u64) -> Result<usize, StoreError> {
    let len = std::fs::metadata(path)
        .map_err(|e| StoreError::os(path, e))?
        .len();
    match items {
        0 => Ok(1),
        n if len % n == 0 && len > 0 => Ok((len / n) as usize),
        n => Err(StoreError::Damaged {
            path: path.to_path_buf(),
            what: DamagedPart::PartialItems {
                bytes: len,
                entries: n,
            },
        }),
    }
}

/// The manifest's own checksum: a CRC-32 of its JSON without the checksum
/// (floats and maps serialise canonically, so a parsed manifest gives the
/// same JSON back).
pub(super) fn manifest_sum(manifest: &Manifest) -> Result<u32, serde_json::Error> {
    let mut bare = manifest.clone();
    bare.crc32 = None;
    Ok(crc32fast::hash(&serde_json::to_vec(&bare)?))
}

/// Seals the store at `dir` as its files now are: its manifest's own
/// checksum always, its columns' when `columns`. Never part of a run: a
/// test or a fuzzer uses it to make a store whose damage the checksums do
/// not show, so the checks behind them (counts against columns, ranges
/// read) are reached too.
#[doc(hidden)]
pub fn reseal(dir: &std::path::Path, columns: bool) -> Result<(), StoreError> {
    let path = dir.join(super::manifest::MANIFEST_FILE);
    let text = std::fs::read(&path).map_err(|e| StoreError::os(&path, e))?;
    let mut manifest: Manifest =
        serde_json::from_slice(&text).map_err(|e| StoreError::Corrupt {
            path: path.clone(),
            reason: e.to_string(),
        })?;
    // Input-order segments are counted by the points: only a count the
    // coordinates' file can hold is taken at its word.
    let holds = |name: &str| std::fs::metadata(dir.join(name)).map_or(0, |m| m.len());
    if columns && manifest.count <= holds(super::XYZ_FILE) {
        let names: Vec<String> = manifest.checksums.keys().cloned().collect();
        for name in names {
            let ranges = segments(layout_of(&name), &manifest.tiles, manifest.count);
            let items = ranges.last().map_or(0, |r| r.end);
            let column_path = dir.join(&name);
            let Ok(bytes) = item_bytes(&column_path, items) else {
                continue;
            };
            if let Ok(sums) = sums_in(dir, &manifest, &name, bytes) {
                manifest.checksums.insert(name, sums);
            }
        }
    }
    super::save_manifest(dir, &manifest)
}
