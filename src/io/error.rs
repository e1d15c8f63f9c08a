//! Errors of the format layer: each names the file and what is wrong with it.

use std::path::PathBuf;

#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum IoError {
    #[error("{path}: {source}")]
    Os {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error(
        "{path}: unknown format (expected .ply, .xyz/.txt/.csv, .las, .laz, .pcd or .e57; text, PLY and PCD optionally .gz)"
    )]
    UnknownFormat { path: PathBuf },
    #[error("{path}: bad header: {reason}")]
    BadHeader { path: PathBuf, reason: String },
    #[error("{path}: record {record}: {reason}")]
    BadRecord {
        path: PathBuf,
        record: u64,
        reason: String,
    },
    #[error("{path}: truncated: header declares {declared} points, file ends after {found}")]
    Truncated {
        path: PathBuf,
        declared: u64,
        found: u64,
    },
    #[error("{path}: record {record}: coordinate is not finite ({value}); use --skip-invalid to drop such points")]
    NonFinite {
        path: PathBuf,
        record: u64,
        value: f64,
    },
    #[error("{path}: {reason}")]
    Unsupported { path: PathBuf, reason: String },
    #[error("{path}: cannot write here: {reason}")]
    Unwritable { path: PathBuf, reason: String },
    #[error("{path}: LAS: {reason}")]
    Las { path: PathBuf, reason: String },
    #[error("{path}: E57: {reason}")]
    E57 { path: PathBuf, reason: String },
    #[error("{path}: file is empty (no header, no points)")]
    Empty { path: PathBuf },
}

impl IoError {
    pub fn os(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        IoError::Os {
            path: path.into(),
            source,
        }
    }
}
