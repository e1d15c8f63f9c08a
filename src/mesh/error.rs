//! Errors of the mesh layer: invalid mesh data and failed mesh output, each
//! naming the triangle, vertex or file concerned.

use crate::io::IoError;
use std::path::PathBuf;

#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum MeshError {
    #[error(
        "triangle {triangle}: vertex index {index} out of range (mesh has {vertex_count} vertices)"
    )]
    IndexOutOfRange {
        triangle: u64,
        index: u32,
        vertex_count: u64,
    },
    #[error("vertex {vertex}: coordinate is not finite ({value})")]
    NonFiniteVertex { vertex: u64, value: f64 },
    #[error("{path}: vertex {vertex}: coordinate is not finite ({value})")]
    NonFiniteOutput {
        path: PathBuf,
        vertex: u64,
        value: f64,
    },
    #[error("{path}: {count} vertices exceed the format's limit of {limit}")]
    TooManyVertices {
        path: PathBuf,
        count: u64,
        limit: u64,
    },
    #[error("{path}: triangle {triangle} refers to vertex {index}, but only {vertex_count} vertices were written")]
    DanglingIndex {
        path: PathBuf,
        triangle: u64,
        index: u32,
        vertex_count: u64,
    },
    #[error(transparent)]
    Io(#[from] IoError),
}

/// The first non-finite coordinate of `p`, if any (for error messages).
pub(crate) fn non_finite_coordinate(p: glam::DVec3) -> Option<f64> {
    p.to_array().into_iter().find(|c| !c.is_finite())
}
