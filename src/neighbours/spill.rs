//! Tile results on disk, so the output can be written in input order while
//! tiles finish in spatial order, without holding all lists in memory.
//!
//! Two scratch files beside the store, removed on drop:
//! - `records`: per tile (in tile order) its core points' records sorted by
//!   id, each `id, count: u32, count neighbour ids` (ids in the output's id
//!   width, little-endian);
//! - `index`: per tile one row of `windows + 1` u64 byte offsets into
//!   `records`: entry `w` is where the tile's first record with
//!   `id >= w * window` starts, the last entry where the tile's records end.
//!
//! Since each tile's records are sorted by id, the records of output window
//! `w` are one contiguous byte range per tile, found from the index in two
//! positioned reads. The output pass reads one window at a time: memory is
//! one window's lists, whatever the point count.

use super::csr::{IdWidth, WindowLists};
use super::kernel::NeighboursTile;
use super::NeighboursError;
use crate::io::scratch::ScratchFile;
use crate::io::IoError;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

/// Geometry of the output windows: `[w * window, (w + 1) * window)`.
#[derive(Clone, Copy, Debug)]
pub struct Windows {
    pub points: u64,
    pub window: u64,
}

impl Windows {
    pub fn new(points: u64, window: u64) -> Self {
        Windows {
            points,
            window: window.max(1),
        }
    }

    pub fn count(&self) -> u64 {
        self.points.div_ceil(self.window)
    }

    /// Input ids of window `w`.
    pub fn range(&self, w: u64) -> std::ops::Range<u64> {
        let lo = (w * self.window).min(self.points);
        lo..(lo + self.window).min(self.points)
    }
}

/// Writes tile results as they arrive (in tile order, on one thread).
pub struct Spill {
    records: BufWriter<File>,
    index: BufWriter<File>,
    guards: [ScratchFile; 2],
    windows: Windows,
    width: IdWidth,
    written: u64,
    tiles: u64,
    buf: Vec<u8>,
}

impl Spill {
    /// Creates the two scratch files in `dir` (names carry the process id).
    pub fn create(dir: &Path, windows: Windows, width: IdWidth) -> Result<Self, IoError> {
        let pid = std::process::id();
        let records = ScratchFile::create(dir.join(format!(".neighbours-{pid}.records")))?;
        let index = ScratchFile::create(dir.join(format!(".neighbours-{pid}.index")))?;
        let open = |s: &ScratchFile| {
            s.file
                .try_clone()
                .map(|f| BufWriter::with_capacity(1 << 20, f))
                .map_err(|e| IoError::os(&s.path, e))
        };
        Ok(Spill {
            records: open(&records)?,
            index: open(&index)?,
            guards: [records, index],
            windows,
            width,
            written: 0,
            tiles: 0,
            buf: Vec::new(),
        })
    }

    /// Appends one tile's records (sorted by id) and its index row.
    pub fn push_tile(&mut self, tile: &NeighboursTile) -> Result<(), IoError> {
        let mut row = Vec::with_capacity(self.windows.count() as usize + 1);
        let mut w = 0;
        for (i, &id) in tile.ids.iter().enumerate() {
            while w * self.windows.window <= id && w <= self.windows.count() {
                row.push(self.written);
                w += 1;
            }
            let list = &tile.neighbours[tile.offsets[i] as usize..tile.offsets[i + 1] as usize];
            self.encode(id, list);
            self.write_buf(0)?;
        }
        row.resize(self.windows.count() as usize + 1, self.written);
        self.buf.clear();
        row.iter()
            .for_each(|o| self.buf.extend_from_slice(&o.to_le_bytes()));
        self.write_buf(1)?;
        self.tiles += 1;
        Ok(())
    }

    fn encode(&mut self, id: u64, list: &[u64]) {
        self.buf.clear();
        self.width.put(id, &mut self.buf);
        // Lists are at most k * (max_iterations + 1) long, far below u32.
        self.buf
            .extend_from_slice(&(list.len() as u32).to_le_bytes());
        list.iter().for_each(|&n| self.width.put(n, &mut self.buf));
    }

    fn write_buf(&mut self, which: usize) -> Result<(), IoError> {
        let out = if which == 0 {
            &mut self.records
        } else {
            &mut self.index
        };
        out.write_all(&self.buf)
            .map_err(|e| IoError::os(&self.guards[which].path, e))?;
        if which == 0 {
            self.written += self.buf.len() as u64;
        }
        Ok(())
    }

    /// Flushes and turns the spill into its window reader.
    pub fn finish(mut self) -> Result<SpillReader, IoError> {
        self.records
            .flush()
            .map_err(|e| IoError::os(&self.guards[0].path, e))?;
        self.index
            .flush()
            .map_err(|e| IoError::os(&self.guards[1].path, e))?;
        let [records, index] = self.guards;
        Ok(SpillReader {
            records,
            index,
            windows: self.windows,
            width: self.width,
            tiles: self.tiles,
            raw: Vec::new(),
            slots: Vec::new(),
        })
    }
}

/// Reads the spilled records back one output window at a time.
pub struct SpillReader {
    records: ScratchFile,
    index: ScratchFile,
    windows: Windows,
    width: IdWidth,
    tiles: u64,
    raw: Vec<u8>,
    /// Per slot of the window: (record byte position in `raw`, count).
    slots: Vec<Option<(usize, u32)>>,
}

impl SpillReader {
    /// Fills `out` with the lists of window `w`; every id of the window must
    /// have exactly one record.
    pub fn read_window(&mut self, w: u64, out: &mut WindowLists) -> Result<(), NeighboursError> {
        let range = self.windows.range(w);
        self.gather(w)?;
        self.slots.clear();
        self.slots.resize((range.end - range.start) as usize, None);
        let width = self.width.bytes();
        let mut pos = 0;
        while pos < self.raw.len() {
            let header = self
                .raw
                .get(pos..pos + width + 4)
                .ok_or_else(|| corrupt(ScratchFault::CutRecord))?;
            let id = self.width.get(&header[..width]);
            let count = u32::from_le_bytes([
                header[width],
                header[width + 1],
                header[width + 2],
                header[width + 3],
            ]);
            let slot = id
                .checked_sub(range.start)
                .filter(|_| range.contains(&id))
                .ok_or_else(|| {
                    corrupt(ScratchFault::OutsideWindow {
                        id,
                        window: range.clone(),
                    })
                })?;
            match &mut self.slots[slot as usize] {
                Some(_) => return Err(corrupt(ScratchFault::Twice { id })),
                s => *s = Some((pos + width + 4, count)),
            }
            pos += width + 4 + count as usize * width;
        }
        if pos != self.raw.len() {
            return Err(corrupt(ScratchFault::CutRecord));
        }
        self.decode(range.start, out)
    }

    /// Concatenates every tile's byte range for window `w` into `raw`.
    fn gather(&mut self, w: u64) -> Result<(), NeighboursError> {
        self.raw.clear();
        let row = self.windows.count() + 1;
        let mut pair = [0u8; 16];
        for t in 0..self.tiles {
            self.index.read_at(&mut pair, (t * row + w) * 8)?;
            let (lo, hi) = (IdWidth::U64.get(&pair[..8]), IdWidth::U64.get(&pair[8..]));
            if hi < lo {
                return Err(corrupt(ScratchFault::BackwardRange {
                    tile: t,
                    window: w,
                    lo,
                    hi,
                }));
            }
            let at = self.raw.len();
            self.raw.resize(at + (hi - lo) as usize, 0);
            self.records.read_at(&mut self.raw[at..], lo)?;
        }
        Ok(())
    }

    fn decode(&self, first: u64, out: &mut WindowLists) -> Result<(), NeighboursError> {
        let width = self.width.bytes();
        out.first = first;
        out.offsets.clear();
        out.neighbours.clear();
        out.offsets.push(0);
        for (i, slot) in self.slots.iter().enumerate() {
            let (at, count) = slot.ok_or_else(|| {
                corrupt(ScratchFault::NoRecord {
                    id: first + i as u64,
                })
            })?;
            let bytes = &self.raw[at..at + count as usize * width];
            out.neighbours
                .extend(bytes.chunks_exact(width).map(|b| self.width.get(b)));
            out.offsets.push(out.neighbours.len() as u64);
        }
        Ok(())
    }
}

fn corrupt(fault: ScratchFault) -> NeighboursError {
    NeighboursError::Scratch { fault }
}

/// What does not add up in the spilled per-tile neighbour lists.
#[derive(Clone, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum ScratchFault {
    /// A record runs past the end of the bytes gathered.
    CutRecord,
    /// A record names a point outside the window being read.
    OutsideWindow {
        /// The point's id.
        id: u64,
        /// The window's ids.
        window: std::ops::Range<u64>,
    },
    /// Two records name the same point.
    Twice {
        /// The point's id.
        id: u64,
    },
    /// A tile's byte range for a window ends before it starts.
    BackwardRange {
        /// 0-based index of the tile.
        tile: u64,
        /// 0-based index of the window.
        window: u64,
        /// Where the range starts, in bytes.
        lo: u64,
        /// Where it ends.
        hi: u64,
    },
    /// No record names a point of the window.
    NoRecord {
        /// The point's id.
        id: u64,
    },
}

impl std::fmt::Display for ScratchFault {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ScratchFault::CutRecord => f.write_str("cut record"),
            ScratchFault::OutsideWindow { id, window } => {
                write!(f, "id {id} outside window {window:?}")
            }
            ScratchFault::Twice { id } => write!(f, "id {id} twice"),
            ScratchFault::BackwardRange {
                tile,
                window,
                lo,
                hi,
            } => {
                write!(f, "tile {tile} window {window}: range {lo}..{hi}")
            }
            ScratchFault::NoRecord { id } => write!(f, "no record for id {id}"),
        }
    }
}
