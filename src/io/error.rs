//! Errors of the format layer: each names the file and what is wrong with it.

use super::reasons::{E57Reason, LasReason, Trailing, UnwritableReason};
use std::path::PathBuf;

/// Errors of the format layer; every variant names the file it concerns.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum IoError {
    /// The operating system refused a read or write of `path`.
    #[error("{path}: {source}")]
    Os {
        /// The file read or written.
        path: PathBuf,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
    /// An output names the input itself: writing it would destroy the input.
    #[error("{path}: output would overwrite the input")]
    OverwritesInput {
        /// The output asked for.
        path: PathBuf,
    },
    /// The file name's extension is none scanmesh reads or writes.
    #[error(
        "{path}: unknown format (expected .ply, .xyz/.txt/.csv, .las, .laz, .pcd or .e57; text, PLY and PCD optionally .gz)"
    )]
    UnknownFormat {
        /// The file whose format is unknown.
        path: PathBuf,
    },
    /// The header is malformed or declares something unusable.
    #[error("{path}: bad header: {reason}")]
    BadHeader {
        /// The file read.
        path: PathBuf,
        /// What is wrong with the header.
        reason: String,
    },
    /// A record (point) cannot be parsed.
    #[error("{path}: record {record}: {reason}")]
    BadRecord {
        /// The file read.
        path: PathBuf,
        /// 0-based index of the record in the file.
        record: u64,
        /// What is wrong with the record.
        reason: String,
    },
    /// The file ends before the number of points its header declares.
    #[error("{path}: truncated: header declares {declared} points, file ends after {found}")]
    Truncated {
        /// The file read.
        path: PathBuf,
        /// Points the header declares.
        declared: u64,
        /// Points the file holds.
        found: u64,
    },
    /// The file holds data past the end its header declares: more records
    /// than the declared count, or bytes after the last declared element.
    /// Zero bytes there are taken as padding, not as data.
    #[error("{path}: more data than the header declares ({declared} points): {found}")]
    TrailingData {
        /// The file read.
        path: PathBuf,
        /// Points the header declares.
        declared: u64,
        /// Bytes after the declared data, where the body is binary (at
        /// least this many: counting stops after a bound).
        extra_bytes: Option<u64>,
        /// What follows the declared data.
        found: Trailing,
    },
    /// The last line of a text body has no end of line, so it may be cut
    /// inside its last number (an unfinished copy or download).
    #[error(
        "{path}: line {line}: no end of line after the last line: the file may be cut short; if it is whole, end it with a newline"
    )]
    CutShort {
        /// The file read.
        path: PathBuf,
        /// 0-based index of the record on that line.
        record: u64,
        /// 1-based line number, as in an editor.
        line: u64,
    },
    /// A record has a NaN or infinite coordinate and the policy rejects such records.
    #[error("{path}: record {record}: coordinate is not finite ({value})")]
    NonFinite {
        /// The file read.
        path: PathBuf,
        /// 0-based index of the record in the file.
        record: u64,
        /// The offending coordinate value.
        value: f64,
    },
    /// The file uses a feature scanmesh does not support, or a request does not fit the file.
    #[error("{path}: {reason}")]
    Unsupported {
        /// The file concerned.
        path: PathBuf,
        /// What is unsupported.
        reason: String,
    },
    /// An output cannot be written where asked (no file name, unwritable directory, ...).
    #[error("{path}: cannot write here: {reason}")]
    Unwritable {
        /// The output path.
        path: PathBuf,
        /// Why it cannot be written.
        reason: UnwritableReason,
    },
    /// A LAS or LAZ file cannot be read or written: the LAS library's
    /// error, or what scanmesh finds wrong.
    #[error("{path}: LAS: {reason}")]
    Las {
        /// The file concerned.
        path: PathBuf,
        /// What is wrong: the LAS library's error, or ours (boxed: the
        /// error stays small).
        reason: Box<LasReason>,
    },
    /// A point's value does not fit the LAS point format written.
    #[error("{path}: point {record} has {field} {value}; LAS point format {format} holds up to {max}: {}", holder(*.holds))]
    LasValue {
        /// The output file.
        path: PathBuf,
        /// 0-based index of the point in the output.
        record: u64,
        /// The field: "class" or "return number".
        field: &'static str,
        /// The point's value.
        value: u32,
        /// The point format written.
        format: u8,
        /// The largest value that format holds.
        max: u32,
        /// A point format that holds the value (LAS 1.4), if any does.
        holds: Option<u8>,
    },
    /// The E57 library reported an error, or the file's structure is unusable.
    #[error("{path}: E57: {reason}")]
    E57 {
        /// The file concerned.
        path: PathBuf,
        /// What is wrong: the E57 library's error, or ours (boxed: the
        /// error stays small).
        reason: Box<E57Reason>,
    },
    /// The file has no header and no points.
    #[error("{path}: file is empty (no header, no points)")]
    Empty {
        /// The empty file.
        path: PathBuf,
    },
}

/// Where a LAS value that does not fit goes instead.
fn holder(holds: Option<u8>) -> String {
    match holds {
        Some(f) => format!("point format {f} (LAS 1.4) holds it"),
        None => "no LAS point format holds it".into(),
    }
}

impl IoError {
    /// An operating-system error on `path`.
    pub fn os(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        IoError::Os {
            path: path.into(),
            source,
        }
    }
}
