//! Errors of the synthetic-scan generators: bad shape parameters, bad meshes.

/// Why a shape cannot be sampled. Checked once when a sampler is built, so
/// sampling itself never fails.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SynthError {
    #[error("{shape}: parameter `{name}` = {value} is invalid: {requirement}")]
    BadParameter {
        shape: &'static str,
        name: &'static str,
        value: f64,
        requirement: &'static str,
    },
    #[error("noise sigma {0} must be finite and >= 0")]
    BadNoise(f64),
    #[error("mesh: vertex {index} is not finite")]
    NonFiniteVertex { index: usize },
    #[error("mesh: face {face} refers to vertex {vertex}, but there are only {vertex_count}")]
    FaceIndexOutOfRange {
        face: usize,
        vertex: u32,
        vertex_count: usize,
    },
    #[error("mesh: no face has positive area ({faces} faces)")]
    NoArea { faces: usize },
    #[error("mesh: {faces} faces; at most 2^32 can be sampled")]
    TooManyFaces { faces: usize },
    #[error("terrain: building {index} {reason}")]
    BadBuilding { index: usize, reason: &'static str },
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
