//! Flat little-endian column files: mapped for reading range by range,
//! written with positioned writes. The one module that needs `unsafe` (the
//! memory map); every map is dropped as soon as its range is decoded, so
//! touched pages do not pile up in RSS.
#![allow(unsafe_code)]

use super::StoreError;
use memmap2::MmapOptions;
use std::fs::File;
use std::os::unix::fs::FileExt;
use std::path::{Path, PathBuf};

/// A column file of fixed-size items.
#[derive(Debug)]
pub struct Column {
    path: PathBuf,
    file: File,
    item_bytes: usize,
}

impl Column {
    /// Opens the existing column file `path` of `item_bytes`-byte items, for writing too when `writable`.
    pub fn open(path: &Path, item_bytes: usize, writable: bool) -> Result<Self, StoreError> {
        let file = File::options()
            .read(true)
            .write(writable)
            .open(path)
            .map_err(|e| StoreError::os(path, e))?;
        Ok(Column {
            path: path.to_path_buf(),
            file,
            item_bytes,
        })
    }

    /// Creates (or truncates) a column sized for `items` items, zero-filled
    /// (sparse where the file system allows).
    pub fn create(path: &Path, item_bytes: usize, items: u64) -> Result<Self, StoreError> {
        let file = File::options()
            .read(true)
            .write(true)
            .create(true)
            .truncate(true)
            .open(path)
            .map_err(|e| StoreError::os(path, e))?;
        file.set_len(items * item_bytes as u64)
            .map_err(|e| StoreError::os(path, e))?;
        Ok(Column {
            path: path.to_path_buf(),
            file,
            item_bytes,
        })
    }

    /// The column's file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Whole items the file holds.
    pub fn items(&self) -> Result<u64, StoreError> {
        let meta = self
            .file
            .metadata()
            .map_err(|e| StoreError::os(&self.path, e))?;
        Ok(meta.len() / self.item_bytes.max(1) as u64)
    }

    /// Calls `f` with the raw bytes of items `[first, first + count)`.
    pub fn with_bytes<R>(
        &self,
        first: u64,
        count: u64,
        f: impl FnOnce(&[u8]) -> R,
    ) -> Result<R, StoreError> {
        let item = self.item_bytes as u64;
        // A corrupt manifest may ask for any range: checked, not wrapped.
        let range = count
            .checked_mul(item)
            .and_then(|len| Some((first.checked_mul(item)?, len)))
            .and_then(|(offset, len)| Some((offset, len, offset.checked_add(len)?)));
        let Some((offset, len, end)) = range else {
            return Err(StoreError::Corrupt {
                path: self.path.clone(),
                reason: format!("range of {count} items from {first} asked"),
            });
        };
        if len == 0 {
            return Ok(f(&[]));
        }
        let file_len = self
            .file
            .metadata()
            .map_err(|e| StoreError::os(&self.path, e))?
            .len();
        if end > file_len {
            return Err(StoreError::Corrupt {
                path: self.path.clone(),
                reason: format!(
                    "column holds {} bytes, range {}..{} asked",
                    file_len, offset, end
                ),
            });
        }
        // SAFETY: the store's column files are private to scanmesh and are
        // truncated only through `&mut PointStore` (`release_positions`), so
        // never while a map of them is alive; the range was checked against
        // the file length above. The map lives only inside this call.
        let map = unsafe {
            MmapOptions::new()
                .offset(offset)
                .len(len as usize)
                .map(&self.file)
        }
        .map_err(|e| StoreError::os(&self.path, e))?;
        Ok(f(&map))
    }

    /// Reads the raw bytes of items `[first, first + count)` into `buf`
    /// (replacing its contents) with a positioned read: for scattered
    /// small reads, where a map per read would cost more than it saves.
    pub fn read_items(&self, first: u64, count: u64, buf: &mut Vec<u8>) -> Result<(), StoreError> {
        let item = self.item_bytes as u64;
        buf.clear();
        buf.resize((count * item) as usize, 0);
        self.file
            .read_exact_at(buf, first * item)
            .map_err(|e| StoreError::os(&self.path, e))
    }

    /// Writes raw bytes at item position `first`.
    pub fn write_bytes(&self, first: u64, bytes: &[u8]) -> Result<(), StoreError> {
        self.file
            .write_all_at(bytes, first * self.item_bytes as u64)
            .map_err(|e| StoreError::os(&self.path, e))
    }

    /// Reads `count` f32 items from item `first` into `out` (replacing its contents); one item is `item_bytes / 4` floats.
    pub fn read_f32(&self, first: u64, count: u64, out: &mut Vec<f32>) -> Result<(), StoreError> {
        out.clear();
        self.with_bytes(first, count, |b| {
            out.extend(
                b.chunks_exact(4)
                    .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])),
            )
        })
    }

    /// Reads `count` u64 items from item `first` into `out` (replacing its contents).
    pub fn read_u64(&self, first: u64, count: u64, out: &mut Vec<u64>) -> Result<(), StoreError> {
        out.clear();
        self.with_bytes(first, count, |b| {
            out.extend(
                b.chunks_exact(8)
                    .map(|c| u64::from_le_bytes([c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]])),
            )
        })
    }

    /// Reads `count` u32 items from item `first` into `out` as u64
    /// (replacing its contents).
    pub fn read_u32_wide(
        &self,
        first: u64,
        count: u64,
        out: &mut Vec<u64>,
    ) -> Result<(), StoreError> {
        out.clear();
        self.with_bytes(first, count, |b| {
            out.extend(
                b.chunks_exact(4)
                    .map(|c| u64::from(u32::from_le_bytes([c[0], c[1], c[2], c[3]]))),
            )
        })
    }

    /// Reads `count` u8 items from item `first` into `out` (replacing its contents).
    pub fn read_u8(&self, first: u64, count: u64, out: &mut Vec<u8>) -> Result<(), StoreError> {
        out.clear();
        self.with_bytes(first, count, |b| out.extend_from_slice(b))
    }

    // The byte buffers are sized up front: collecting a `flat_map` grows
    // them by doubling (its size hint is 0), copying each several times.
    /// Writes `values` (f32, `item_bytes / 4` per item) from item `first` on.
    pub fn write_f32(&self, first: u64, values: &[f32]) -> Result<(), StoreError> {
        let mut bytes = Vec::with_capacity(values.len() * 4);
        values
            .iter()
            .for_each(|v| bytes.extend_from_slice(&v.to_le_bytes()));
        self.write_bytes(first, &bytes)
    }

    /// Writes `values` (each at most `u32::MAX`) as one u32 per item from
    /// item `first` on.
    pub fn write_u32_narrow(&self, first: u64, values: &[u64]) -> Result<(), StoreError> {
        let mut bytes = Vec::with_capacity(values.len() * 4);
        for &v in values {
            let v = u32::try_from(v).map_err(|_| StoreError::Corrupt {
                path: self.path().to_path_buf(),
                reason: format!("{v} does not fit a u32 item"),
            })?;
            bytes.extend_from_slice(&v.to_le_bytes());
        }
        self.write_bytes(first, &bytes)
    }

    /// Flushes the column's data to disk.
    pub fn sync(&self) -> Result<(), StoreError> {
        self.file
            .sync_data()
            .map_err(|e| StoreError::os(&self.path, e))
    }
}
