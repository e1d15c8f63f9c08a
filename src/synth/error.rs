//! Errors of the synthetic-scan generators: bad shape parameters, bad meshes.

/// Why a shape cannot be sampled. Checked once when a sampler is built, so
/// sampling itself never fails.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SynthError {
    /// A shape parameter is out of its valid range.
    #[error("{shape}: parameter `{name}` = {value} is invalid: {requirement}")]
    BadParameter {
        /// The shape's name.
        shape: &'static str,
        /// The parameter's name.
        name: &'static str,
        /// The value given.
        value: f64,
        /// What the parameter must satisfy.
        requirement: &'static str,
    },
    /// The noise standard deviation is negative or not finite.
    #[error("noise sigma {0} must be finite and >= 0")]
    BadNoise(f64),
    /// A mesh vertex has a NaN or infinite coordinate.
    #[error("mesh: vertex {index} is not finite")]
    NonFiniteVertex {
        /// 0-based index of the vertex.
        index: usize,
    },
    /// A mesh face names a vertex the mesh does not have.
    #[error("mesh: face {face} refers to vertex {vertex}, but there are only {vertex_count}")]
    FaceIndexOutOfRange {
        /// 0-based index of the face.
        face: usize,
        /// The vertex index it names.
        vertex: u32,
        /// Vertices the mesh has.
        vertex_count: usize,
    },
    /// No face of the mesh has positive area, so there is nothing to sample.
    #[error("mesh: no face has positive area ({faces} faces)")]
    NoArea {
        /// Faces of the mesh.
        faces: usize,
    },
    /// The mesh has more faces than the sampler can index.
    #[error("mesh: {faces} faces; at most 2^32 can be sampled")]
    TooManyFaces {
        /// Faces of the mesh.
        faces: usize,
    },
    /// A terrain building is degenerate or out of the square.
    #[error("terrain: building {index} {reason}")]
    BadBuilding {
        /// 0-based index of the building.
        index: usize,
        /// What is wrong with it.
        reason: &'static str,
    },
}

/// `value` if it is finite and strictly positive.
pub(crate) fn positive(
    shape: &'static str,
    name: &'static str,
    value: f64,
) -> Result<f64, SynthError> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(SynthError::BadParameter {
            shape,
            name,
            value,
            requirement: "must be finite and > 0",
        })
    }
}

/// `value` if it is finite (any sign).
pub(crate) fn finite(
    shape: &'static str,
    name: &'static str,
    value: f64,
) -> Result<f64, SynthError> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(SynthError::BadParameter {
            shape,
            name,
            value,
            requirement: "must be finite",
        })
    }
}

/// `Err(BadParameter)` unless `ok`.
pub(crate) fn require(
    ok: bool,
    shape: &'static str,
    name: &'static str,
    value: f64,
    requirement: &'static str,
) -> Result<(), SynthError> {
    if ok {
        Ok(())
    } else {
        Err(SynthError::BadParameter {
            shape,
            name,
            value,
            requirement,
        })
    }
}
