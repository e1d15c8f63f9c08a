//! Errors of the mesh layer: invalid mesh data and failed mesh output, each
//! naming the triangle, vertex or file concerned.

use super::audit::{failures_text, Failure, MeshAudit, Promise};
use crate::io::IoError;
use std::path::PathBuf;

/// Errors of the mesh layer: invalid mesh data and failed mesh output.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum MeshError {
    /// A triangle names a vertex the mesh does not have.
    #[error(
        "triangle {triangle}: vertex index {index} out of range (mesh has {vertex_count} vertices)"
    )]
    IndexOutOfRange {
        /// 0-based index of the triangle.
        triangle: u64,
        /// The vertex index it names.
        index: u32,
        /// Vertices the mesh has.
        vertex_count: u64,
    },
    /// A vertex has a NaN or infinite coordinate.
    #[error("vertex {vertex}: coordinate is not finite ({value})")]
    NonFiniteVertex {
        /// 0-based index of the vertex.
        vertex: u64,
        /// The offending coordinate value.
        value: f64,
    },
    /// A vertex handed to a mesh writer has a NaN or infinite coordinate.
    #[error("{path}: vertex {vertex}: coordinate is not finite ({value})")]
    NonFiniteOutput {
        /// The output file.
        path: PathBuf,
        /// 0-based index of the vertex in the output.
        vertex: u64,
        /// The offending coordinate value.
        value: f64,
    },
    /// The mesh has more vertices than the output format can index.
    #[error("{path}: {count} vertices exceed the format's limit of {limit}")]
    TooManyVertices {
        /// The output file.
        path: PathBuf,
        /// Vertices of the mesh.
        count: u64,
        /// Most vertices the format can index.
        limit: u64,
    },
    /// A triangle written refers to a vertex that was never written.
    #[error("{path}: triangle {triangle} refers to vertex {index}, but only {vertex_count} vertices were written")]
    DanglingIndex {
        /// The output file.
        path: PathBuf,
        /// 0-based index of the triangle in the output.
        triangle: u64,
        /// The vertex index it names.
        index: u32,
        /// Vertices written.
        vertex_count: u64,
    },
    /// The mesh written breaks what the run promised of it (a closed
    /// surface, or the projection's directed edges): it is written, but
    /// under a name that says it is incomplete, never the name asked for.
    #[error("{path}: the mesh does not keep its promise ({promise}): {failures_text}; written incomplete as {written} (checked: {audit})", failures_text = failures_text(.failures))]
    PromiseBroken {
        /// The output asked for (not written).
        path: PathBuf,
        /// Where the mesh went: `NAME.incomplete.EXT`.
        written: PathBuf,
        /// What was promised.
        promise: Promise,
        /// What of it broke, with the counts.
        failures: Vec<Failure>,
        /// The whole audit of the mesh written.
        audit: Box<MeshAudit>,
    },
    /// A selection of points was given for a reference that is a mesh.
    #[error(
        "{path}: --classes and --returns select points of a point file; this reference is a mesh"
    )]
    SelectionOfAMesh {
        /// The reference.
        path: PathBuf,
    },
    /// The output file could not be written.
    #[error(transparent)]
    Io(#[from] IoError),
}

/// The first non-finite coordinate of `p`, if any (for error messages).
pub(crate) fn non_finite_coordinate(p: glam::DVec3) -> Option<f64> {
    p.to_array().into_iter().find(|c| !c.is_finite())
}
