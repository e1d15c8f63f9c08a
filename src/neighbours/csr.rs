//! The neighbourhood output files, written one input-order window
//! ([`WindowLists`]) at a time under a temporary name ([`AtomicFile`]) and
//! renamed into place only when complete.
//!
//! Binary CSR (`--format bin`), all integers little-endian:
//!
//! | byte offset            | size           | field                                   |
//! |------------------------|----------------|-----------------------------------------|
//! | 0                      | 8              | magic `SMNBR001`                        |
//! | 8                      | 8              | u64 point count `n`                     |
//! | 16                     | 8              | u64 total neighbour count `m`           |
//! | 24                     | 1              | u8 id width `w`: 4 (u32) or 8 (u64)     |
//! | 25                     | 7              | zero padding                            |
//! | 32                     | 8 (n + 1)      | u64 offsets, `offsets[0] = 0`, `offsets[n] = m` |
//! | 32 + 8 (n + 1)         | w m            | neighbour ids                           |
//!
//! The neighbours of point `i` (0-based input order) are ids
//! `offsets[i]..offsets[i + 1]`, sorted by (distance, id). `w` is 4 whenever
//! every id fits a u32 (`n <= 2^32`). The padding (not in the field
//! list) keeps the offsets 8-byte aligned for readers that map the file.
//!
//! Text (`--format txt`): one line per point in input order, its id then its
//! neighbours' ids, separated by single spaces.

use crate::io::{AtomicFile, IoError};
use std::io::Write;
use std::os::unix::fs::FileExt;
use std::path::{Path, PathBuf};

pub const MAGIC: &[u8; 8] = b"SMNBR001";
pub const HEADER_BYTES: u64 = 32;

/// Bytes per id in the CSR file and the scratch records.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum IdWidth {
    /// Four-byte little-endian ids.
    U32,
    /// Eight-byte little-endian ids.
    U64,
}

impl IdWidth {
    /// The narrowest width holding every id below `points`.
    pub fn for_points(points: u64) -> Self {
        if points <= 1 << 32 {
            IdWidth::U32
        } else {
            IdWidth::U64
        }
    }

    /// Bytes of one id.
    pub fn bytes(self) -> usize {
        match self {
            IdWidth::U32 => 4,
            IdWidth::U64 => 8,
        }
    }

    fn from_byte(b: u8) -> Option<Self> {
        match b {
            4 => Some(IdWidth::U32),
            8 => Some(IdWidth::U64),
            _ => None,
        }
    }

    /// Appends `v` (which must fit) little-endian.
    pub fn put(self, v: u64, out: &mut Vec<u8>) {
        out.extend_from_slice(&v.to_le_bytes()[..self.bytes()]);
    }

    /// Reads one id from the first `bytes()` bytes of `b`.
    pub fn get(self, b: &[u8]) -> u64 {
        let mut a = [0u8; 8];
        let w = self.bytes();
        a[..w].copy_from_slice(&b[..w]);
        u64::from_le_bytes(a)
    }
}

/// Output format of `scanmesh neighbors`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum OutputFormat {
    /// The binary CSR layout above.
    #[default]
    #[value(
        name = "bin",
        help = "Binary CSR: header, u64 offsets, u32/u64 neighbour ids"
    )]
    Csr,
    /// One text line per point.
    #[value(
        name = "txt",
        help = "One line per point: its id, then its neighbours' ids"
    )]
    Text,
}

/// One output window's lists: `neighbours[offsets[i]..offsets[i + 1]]` is
/// the list of point `first + i`.
#[derive(Debug, Default)]
pub struct WindowLists {
    pub first: u64,
    pub offsets: Vec<u64>,
    pub neighbours: Vec<u64>,
}

impl WindowLists {
    pub fn len(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    pub fn list(&self, i: usize) -> &[u64] {
        &self.neighbours[self.offsets[i] as usize..self.offsets[i + 1] as usize]
    }
}

/// Writes windows of lists, in input order, to a temporary file.
pub struct ListWriter {
    file: AtomicFile,
    format: OutputFormat,
    points: u64,
    width: IdWidth,
    next_id: u64,
    next_offset: u64,
    /// Bytes written so far (text).
    written: u64,
    buf: Vec<u8>,
}

impl ListWriter {
    /// Opens the temporary file for `points` lists.
    pub fn create(path: &Path, format: OutputFormat, points: u64) -> Result<Self, IoError> {
        Ok(ListWriter {
            file: AtomicFile::create(path)?,
            format,
            points,
            width: IdWidth::for_points(points),
            next_id: 0,
            next_offset: 0,
            written: 0,
            buf: Vec::new(),
        })
    }

    /// Appends the next window (its first id must follow the last one).
    pub fn write_window(&mut self, lists: &WindowLists) -> Result<(), IoError> {
        if lists.first != self.next_id || self.next_id + lists.len() as u64 > self.points {
            return Err(self.misuse(format!(
                "window of {} lists at id {} after {} of {}",
                lists.len(),
                lists.first,
                self.next_id,
                self.points
            )));
        }
        match self.format {
            OutputFormat::Csr => self.csr_window(lists)?,
            OutputFormat::Text => self.text_window(lists)?,
        }
        self.next_id += lists.len() as u64;
        self.next_offset += lists.neighbours.len() as u64;
        Ok(())
    }

    fn ids_start(&self) -> u64 {
        HEADER_BYTES + 8 * (self.points + 1)
    }

    fn csr_window(&mut self, lists: &WindowLists) -> Result<(), IoError> {
        self.buf.clear();
        for &o in &lists.offsets[..lists.len()] {
            self.buf
                .extend_from_slice(&(self.next_offset + o).to_le_bytes());
        }
        self.write_at(HEADER_BYTES + 8 * self.next_id)?;
        self.buf.clear();
        for &id in &lists.neighbours {
            self.width.put(id, &mut self.buf);
        }
        self.write_at(self.ids_start() + self.width.bytes() as u64 * self.next_offset)
    }

    fn text_window(&mut self, lists: &WindowLists) -> Result<(), IoError> {
        self.buf.clear();
        for i in 0..lists.len() {
            // Writing into a Vec cannot fail.
            let _ = write!(self.buf, "{}", lists.first + i as u64);
            for id in lists.list(i) {
                let _ = write!(self.buf, " {id}");
            }
            self.buf.push(b'\n');
        }
        self.write_at(self.written)?;
        self.written += self.buf.len() as u64;
        Ok(())
    }

    fn write_at(&mut self, pos: u64) -> Result<(), IoError> {
        let path = self.file.final_path().to_path_buf();
        self.file
            .file()
            .write_all_at(&self.buf, pos)
            .map_err(|e| IoError::os(path, e))
    }

    fn misuse(&self, reason: String) -> IoError {
        IoError::Unsupported {
            path: self.file.final_path().to_path_buf(),
            reason,
        }
    }

    /// Completes the file (CSR: the header and the last offset, now that
    /// the total is known) and renames it into place. Fails, leaving
    /// nothing, unless every list was written.
    pub fn commit(mut self) -> Result<(), IoError> {
        if self.next_id != self.points {
            return Err(self.misuse(format!("{} of {} lists", self.next_id, self.points)));
        }
        if self.format == OutputFormat::Csr {
            self.buf.clear();
            self.buf.extend_from_slice(&self.next_offset.to_le_bytes());
            self.write_at(HEADER_BYTES + 8 * self.points)?;
            self.buf = header(self.points, self.next_offset, self.width);
            self.write_at(0)?;
        }
        self.file.commit()
    }
}

fn header(points: u64, neighbours: u64, width: IdWidth) -> Vec<u8> {
    let mut h = Vec::with_capacity(HEADER_BYTES as usize);
    h.extend_from_slice(MAGIC);
    h.extend_from_slice(&points.to_le_bytes());
    h.extend_from_slice(&neighbours.to_le_bytes());
    h.push(width.bytes() as u8);
    h.resize(HEADER_BYTES as usize, 0);
    h
}

/// A whole CSR file in memory (for tests and small outputs).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Csr {
    /// `neighbours[offsets[i]..offsets[i + 1]]` is the list of point `i`; one more entry than points.
    pub offsets: Vec<u64>,
    /// Every list, concatenated in point order.
    pub neighbours: Vec<u64>,
    /// Width of the ids in the file.
    pub width: IdWidth,
}

impl Csr {
    /// Points (lists) in the file.
    pub fn len(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// Whether the file holds no list.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Neighbours of point `i`.
    pub fn list(&self, i: usize) -> &[u64] {
        &self.neighbours[self.offsets[i] as usize..self.offsets[i + 1] as usize]
    }
}

/// Reads and validates a CSR file: header, size, offsets nondecreasing from
/// 0 to the total, ids below the point count.
pub fn read_csr(path: &Path) -> Result<Csr, IoError> {
    let bytes = std::fs::read(path).map_err(|e| IoError::os(path, e))?;
    let bad = |reason: String| IoError::BadHeader {
        path: PathBuf::from(path),
        reason,
    };
    if bytes.len() < HEADER_BYTES as usize || &bytes[..8] != MAGIC {
        return Err(bad("not a scanmesh neighbour file (magic SMNBR001)".into()));
    }
    let points = IdWidth::U64.get(&bytes[8..]);
    let total = IdWidth::U64.get(&bytes[16..]);
    let width =
        IdWidth::from_byte(bytes[24]).ok_or_else(|| bad(format!("id width {}", bytes[24])))?;
    let expected = points
        .checked_add(1)
        .and_then(|p| p.checked_mul(8))
        .and_then(|o| total.checked_mul(width.bytes() as u64)?.checked_add(o))
        .and_then(|b| b.checked_add(HEADER_BYTES));
    if expected != Some(bytes.len() as u64) {
        return Err(bad(format!(
            "{points} points and {total} neighbours do not fill {} bytes",
            bytes.len()
        )));
    }
    let ids_start = HEADER_BYTES as usize + 8 * (points as usize + 1);
    let offsets: Vec<u64> = bytes[HEADER_BYTES as usize..ids_start]
        .chunks_exact(8)
        .map(|b| IdWidth::U64.get(b))
        .collect();
    let monotone = offsets.windows(2).all(|w| w[0] <= w[1]);
    if offsets.first() != Some(&0) || offsets.last() != Some(&total) || !monotone {
        return Err(bad("offsets do not run from 0 up to the total".into()));
    }
    let neighbours: Vec<u64> = bytes[ids_start..]
        .chunks_exact(width.bytes())
        .map(|b| width.get(b))
        .collect();
    if let Some(id) = neighbours.iter().find(|&&id| id >= points) {
        return Err(bad(format!("neighbour id {id} >= {points} points")));
    }
    Ok(Csr {
        offsets,
        neighbours,
        width,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn window(first: u64, lists: &[&[u64]]) -> WindowLists {
        let mut w = WindowLists {
            first,
            offsets: vec![0],
            neighbours: Vec::new(),
        };
        for l in lists {
            w.neighbours.extend_from_slice(l);
            w.offsets.push(w.neighbours.len() as u64);
        }
        w
    }

    #[test]
    fn csr_round_trips_over_windows_and_text_matches() {
        let dir = tempfile::tempdir().unwrap();
        let lists: [&[u64]; 5] = [&[1, 2], &[], &[0, 4, 3], &[2], &[0]];
        for format in [OutputFormat::Csr, OutputFormat::Text] {
            let path = dir.path().join(format!("{format:?}"));
            let mut w = ListWriter::create(&path, format, 5).unwrap();
            w.write_window(&window(0, &lists[..2])).unwrap();
            w.write_window(&window(2, &lists[2..])).unwrap();
            w.commit().unwrap();
            if format == OutputFormat::Csr {
                let csr = read_csr(&path).unwrap();
                assert_eq!(csr.width, IdWidth::U32);
                assert_eq!(csr.len(), 5);
                for (i, l) in lists.iter().enumerate() {
                    assert_eq!(csr.list(i), *l);
                }
            } else {
                let text = std::fs::read_to_string(&path).unwrap();
                assert_eq!(text, "0 1 2\n1\n2 0 4 3\n3 2\n4 0\n");
            }
        }
    }

    #[test]
    fn incomplete_output_is_not_left() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("short.nbr");
        let mut w = ListWriter::create(&path, OutputFormat::Csr, 3).unwrap();
        w.write_window(&window(0, &[&[1], &[0]])).unwrap();
        assert!(w.write_window(&window(5, &[&[1]])).is_err());
        assert!(w.commit().is_err());
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    }

    #[test]
    fn corrupt_files_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("x.nbr");
        let mut w = ListWriter::create(&path, OutputFormat::Csr, 2).unwrap();
        w.write_window(&window(0, &[&[1], &[0]])).unwrap();
        w.commit().unwrap();
        let good = std::fs::read(&path).unwrap();
        let mut cut = good.clone();
        cut.pop();
        let mut big_id = good.clone();
        let last = big_id.len() - 4;
        big_id[last] = 9;
        let mut absurd = good.clone();
        absurd[8..16].copy_from_slice(&u64::MAX.to_le_bytes());
        for bad in [cut, big_id, absurd, b"SMNBR002".to_vec()] {
            std::fs::write(&path, bad).unwrap();
            assert!(read_csr(&path).is_err());
        }
    }
}
