//! The typed reasons some [`IoError`](super::IoError) variants carry: why
//! an output or scratch place cannot be written, what a LAS or E57 file
//! (or the las or e57 crate) objects to, what follows a file's declared
//! data. Each displays as the words the error has always said.

use glam::DVec3;
use std::fmt;

/// Why a place cannot take an output or scratch files
/// ([`IoError::Unwritable`](super::IoError::Unwritable)).
#[derive(Debug)]
#[non_exhaustive]
pub enum UnwritableReason {
    /// The directory cannot be used (it does not exist, or cannot be read).
    Unusable {
        /// Its role: "output", "scratch".
        role: &'static str,
        /// What the operating system said.
        cause: std::io::Error,
    },
    /// The directory's path names something else than a directory.
    NotADirectory {
        /// Its role: "output", "scratch".
        role: &'static str,
    },
    /// The directory takes no new file.
    NotWritable {
        /// Its role: "output", "scratch".
        role: &'static str,
        /// What the operating system said.
        cause: std::io::Error,
    },
    /// The output's path is a directory.
    OutputIsADirectory,
    /// The volume has too little free space for what the run puts there.
    NoSpace {
        /// What goes there: "scratch files", "output", "scratch files and output".
        what: &'static str,
        /// Bytes it needs.
        needed: u64,
        /// Bytes free.
        free: u64,
        /// Bytes of the free ones kept free for the rest of the machine.
        kept: u64,
    },
}

impl fmt::Display for UnwritableReason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        use crate::units::human_bytes;
        match self {
            UnwritableReason::Unusable { role, cause } => {
                write!(f, "{role} directory cannot be used: {cause}")
            }
            UnwritableReason::NotADirectory { role } => {
                write!(f, "{role} directory is not a directory")
            }
            UnwritableReason::NotWritable { role, cause } => {
                write!(f, "{role} directory is not writable: {cause}")
            }
            UnwritableReason::OutputIsADirectory => f.write_str("output is a directory"),
            UnwritableReason::NoSpace {
                what,
                needed,
                free,
                kept,
            } => write!(
                f,
                "the {what} need about {} here but only {} is free ({} of it kept free)",
                human_bytes(*needed),
                human_bytes(*free),
                human_bytes(*kept)
            ),
        }
    }
}

/// What is wrong with a LAS or LAZ file read or written
/// ([`IoError::Las`](super::IoError::Las)).
#[derive(Debug)]
#[non_exhaustive]
pub enum LasReason {
    /// The las crate's error (not an operating-system one, which is
    /// [`IoError::Os`](super::IoError::Os)).
    Library(las::Error),
    /// The points' bounds, to choose a scale and offset from, are empty or
    /// not finite.
    EmptyBounds,
    /// A LAS output was asked for with neither the points' bounds nor a
    /// scale and offset.
    NoBoundsOrTransform,
    /// The scale and offset cannot quantise coordinates.
    BadTransform,
    /// A point's coordinates do not fit the i32 records under the scale
    /// and offset.
    OutOfRange {
        /// 0-based index of the point in the output.
        record: u64,
        /// Its coordinates.
        point: DVec3,
        /// The scale written.
        scale: DVec3,
        /// The offset written.
        offset: DVec3,
    },
    /// The thread decoding the file stopped without an error of its own.
    DecoderStopped,
}

impl fmt::Display for LasReason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LasReason::Library(e) => write!(f, "{e}"),
            LasReason::EmptyBounds => f.write_str("bounds are empty or not finite"),
            LasReason::NoBoundsOrTransform => {
                f.write_str("LAS output needs the points' bounds or a scale/offset transform")
            }
            LasReason::BadTransform => {
                f.write_str("scale must be finite and positive, offset finite")
            }
            LasReason::OutOfRange {
                record,
                point: p,
                scale,
                offset,
            } => write!(
                f,
                "point {record} ({}, {}, {}) is outside the i32 range of scale {scale} offset {offset}",
                p.x, p.y, p.z
            ),
            LasReason::DecoderStopped => f.write_str("the decoding thread stopped unexpectedly"),
        }
    }
}

/// What follows the data a file's header declares
/// ([`IoError::TrailingData`](super::IoError::TrailingData)).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum Trailing {
    /// A text line that is not blank.
    Line {
        /// 1-based line number.
        line: u64,
        /// What the header declares: "elements" (PLY), "points" (PCD).
        declared: &'static str,
    },
    /// Bytes (not zero padding) after a binary body.
    Bytes {
        /// Bytes after the declared data (all of them when `exact`, else
        /// at least this many).
        bytes: u64,
        /// Whether `bytes` were counted to the end.
        exact: bool,
        /// The body's record size, when its records are the last data.
        record: Option<u64>,
    },
    /// A LAZ chunk table (of chunks of their own sizes) listing more
    /// points than the header declares.
    ChunkPoints {
        /// Points the table lists.
        listed: u64,
    },
    /// A LAZ chunk table listing more chunks than the points need.
    Chunks {
        /// Chunks the table lists.
        listed: usize,
        /// Points per chunk.
        size: u64,
        /// Chunks that hold the declared points.
        needed: u64,
    },
}

impl fmt::Display for Trailing {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Trailing::Line { line, declared } => {
                write!(f, "line {line} follows the declared {declared}")
            }
            Trailing::Bytes {
                bytes,
                exact,
                record,
            } => {
                let at_least = if exact { "" } else { "at least " };
                write!(f, "{at_least}{bytes} bytes follow the declared data")?;
                if let Some(size) = record.filter(|&r| r > 0) {
                    let (whole, rest) = (bytes / size, bytes % size);
                    let records = if whole == 1 { "record" } else { "records" };
                    write!(f, ", {at_least}{whole} whole {records} of {size} bytes")?;
                    if rest > 0 && exact {
                        write!(f, " and {rest} bytes")?;
                    }
                }
                Ok(())
            }
            Trailing::ChunkPoints { listed } => write!(f, "its chunk table lists {listed} points"),
            Trailing::Chunks {
                listed,
                size,
                needed,
            } => write!(
                f,
                "its chunk table lists {listed} chunks of {size} points; {needed} would hold them"
            ),
        }
    }
}

/// What is wrong with an E57 file read or written
/// ([`IoError::E57`](super::IoError::E57)).
#[derive(Debug)]
#[non_exhaustive]
pub enum E57Reason {
    /// The e57 crate's error (its message holds its source's), at a step
    /// of the reading or writing.
    Library {
        /// What was being done.
        step: E57Step,
        /// The e57 crate's error.
        error: ::e57::Error,
    },
    /// The file is shorter than the header every E57 starts with.
    Truncated {
        /// The file's length in bytes.
        bytes: u64,
        /// The header's length in bytes.
        header: u64,
    },
    /// The scan selection names a scan the file does not have.
    NoSuchScan {
        /// The scan named.
        named: usize,
        /// Scans in the file.
        scans: usize,
    },
    /// A scan's descriptor is unusable.
    Scan {
        /// The scan's index in the file.
        index: usize,
        /// What is wrong with it.
        problem: ScanProblem,
    },
    /// The thread decoding the file stopped without an error of its own.
    DecoderStopped,
    /// The thread writing the file stopped without an error of its own.
    WriterStopped,
}

/// A step of reading or writing an E57 file, as its errors name it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum E57Step {
    /// A step named in words ("cannot read the E57 header and XML").
    Named(&'static str),
    /// Reading a scan's records.
    Record {
        /// The scan's index in the file.
        scan: usize,
        /// Records of the scan read before.
        record: u64,
        /// Records of the scan.
        total: u64,
    },
}

/// Why an E57 scan descriptor is unusable.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum ScanProblem {
    /// The pose has a non-finite value.
    PoseNotFinite {
        /// Its rotation quaternion, w x y z.
        rotation: [f64; 4],
        /// Its translation.
        translation: [f64; 3],
    },
    /// The pose's rotation quaternion is (nearly) zero.
    RotationNotNormalisable([f64; 4]),
    /// The records hold neither cartesian nor spherical coordinates.
    NoCoordinates,
    /// Every field is a constant of zero bits: the records' ends cannot be
    /// told.
    ZeroBitFields,
}

impl fmt::Display for E57Reason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            E57Reason::Library { step, error } => write!(f, "{step}: {error}"),
            E57Reason::Truncated { bytes, header } => {
                write!(
                    f,
                    "truncated: {bytes} bytes, less than the {header}-byte header"
                )
            }
            E57Reason::NoSuchScan { named, scans } => write!(
                f,
                "the scan selection names scan {named}, but the file has {scans} (0..{})",
                scans.saturating_sub(1)
            ),
            E57Reason::Scan { index, problem } => write!(f, "scan {index}: {problem}"),
            E57Reason::DecoderStopped => f.write_str("the decoding thread stopped unexpectedly"),
            E57Reason::WriterStopped => f.write_str("the writing thread stopped unexpectedly"),
        }
    }
}

impl fmt::Display for E57Step {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            E57Step::Named(what) => f.write_str(what),
            E57Step::Record {
                scan,
                record,
                total,
            } => write!(f, "scan {scan}: record {record} of {total}"),
        }
    }
}

impl fmt::Display for ScanProblem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ScanProblem::PoseNotFinite {
                rotation,
                translation,
            } => write!(
                f,
                "pose is not finite (rotation {rotation:?}, translation {translation:?})"
            ),
            ScanProblem::RotationNotNormalisable(q) => {
                write!(f, "pose rotation quaternion {q:?} cannot be normalised")
            }
            ScanProblem::NoCoordinates => {
                f.write_str("has neither cartesian nor spherical coordinates")
            }
            ScanProblem::ZeroBitFields => {
                f.write_str("every field is a constant of zero bits; such a scan cannot be decoded")
            }
        }
    }
}
