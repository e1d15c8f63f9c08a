//! Which part of a store fails its checksum, and which column a pass
//! finds missing: the typed fields of [`StoreError`](super::StoreError).

use crate::io::Attribute;

/// The part of a store file that no longer holds what was written to it.
#[derive(Clone, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum DamagedPart {
    /// The manifest has checksums for a different number of segments
    /// than its tiles (or input chunks) make.
    SegmentCount {
        /// Checksums the manifest holds.
        sums: usize,
        /// Segments the column has.
        segments: usize,
    },
    /// One tile's (or block's) segment of a column.
    Tile(usize),
    /// A range of input points of an input-ordered column.
    InputPoints {
        /// The first point.
        start: u64,
        /// One past the last point.
        end: u64,
    },
    /// The file's length is not a whole number of items.
    PartialItems {
        /// The file's length, in bytes.
        bytes: u64,
        /// The items it should hold.
        entries: u64,
    },
    /// The manifest itself.
    Manifest,
    /// The kept copy of a LAS input's header, VLRs or EVLRs.
    LasHeader,
}

impl std::fmt::Display for DamagedPart {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            DamagedPart::SegmentCount { sums, segments } => {
                write!(f, "{sums} checksums for {segments} segments")
            }
            DamagedPart::Tile(k) => write!(f, "tile {k}"),
            DamagedPart::InputPoints { start, end } => write!(f, "input points {start}..{end}"),
            DamagedPart::PartialItems { bytes, entries } => {
                write!(
                    f,
                    "its {bytes} bytes are not whole items for {entries} entries"
                )
            }
            DamagedPart::Manifest => f.write_str("the manifest"),
            DamagedPart::LasHeader => f.write_str("the LAS input's header, VLRs or EVLRs"),
        }
    }
}

/// A column of a store, by what it holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum ColumnName {
    /// A column a pass computes (its file name, as in [`ColumnSpec`](super::ColumnSpec)).
    Computed(&'static str),
    /// An input attribute's column (file `<name>.input`).
    Attribute(Attribute),
}

impl std::fmt::Display for ColumnName {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ColumnName::Computed(name) => f.write_str(name),
            ColumnName::Attribute(a) => write!(f, "{}.input", a.name()),
        }
    }
}
