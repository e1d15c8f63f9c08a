//! What an E57 file says about each of its scans before any point is read:
//! name, record count, pose, which coordinates and attributes its records
//! hold; and the pose as a rigid transform applied in f64.
//!
//! The pose maps a scan's own frame into the file's world frame:
//! `world = R(q) p + t` (ASTM E2807, a Data3D's `pose`, a RigidBody). The
//! standard asks for a unit quaternion; one that is not is normalised here
//! rather than let it scale the scan. A quaternion of length zero, or a
//! non-finite pose, is an error.

use crate::io::{E57Reason, IoError, ScanProblem};
use ::e57::{PointCloud, RecordDataType, RecordName};
use glam::{DMat3, DQuat, DVec3};
use std::path::Path;

/// One scan ("data3D" point cloud) of an E57 file.
#[derive(Clone, Debug, PartialEq)]
pub struct ScanInfo {
    /// Position among the file's scans (what `--scans` selects).
    pub index: usize,
    /// The scan's name, when the file gives one.
    pub name: Option<String>,
    /// The scan's GUID, when the file gives one.
    pub guid: Option<String>,
    /// Records the file declares, valid or not.
    pub records: u64,
    /// Where the scan sits in the world frame: its points are moved by this pose when read.
    pub pose: Pose,
    /// Whether the file gives the pose: without one the points are taken
    /// as they are (the identity), but nothing says where the scanner
    /// stood (merged or converted data often has none), so the scan names
    /// no station.
    pub posed: bool,
    /// Whether the records carry Cartesian coordinates.
    pub cartesian: bool,
    /// Whether the records carry spherical coordinates (range, azimuth, elevation).
    pub spherical: bool,
    /// Point attributes present besides the coordinates, by their E57
    /// names (`intensity`, `color`, `rowIndex`, `returnIndex`, `timeStamp`,
    /// `cartesianInvalidState`, ...).
    pub attributes: Vec<&'static str>,
}

/// A rigid transform: unit rotation quaternion and translation, f64.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    /// `[w, x, y, z]`, normalised.
    pub rotation: [f64; 4],
    /// Translation `[x, y, z]`, applied after the rotation.
    pub translation: [f64; 3],
}

impl Pose {
    /// No rotation, no translation.
    pub const IDENTITY: Pose = Pose {
        rotation: [1.0, 0.0, 0.0, 0.0],
        translation: [0.0; 3],
    };

    /// Whether the pose leaves every point where it is.
    pub fn is_identity(&self) -> bool {
        *self == Pose::IDENTITY
    }

    /// The pose as a matrix and an offset, for the hot loop.
    pub fn transform(&self) -> Transform {
        let [w, x, y, z] = self.rotation;
        Transform {
            rotation: DMat3::from_quat(DQuat::from_xyzw(x, y, z, w)),
            translation: DVec3::from_array(self.translation),
            identity: self.is_identity(),
        }
    }
}

/// [`Pose`] ready to apply.
#[derive(Clone, Copy, Debug)]
pub struct Transform {
    rotation: DMat3,
    translation: DVec3,
    identity: bool,
}

impl Transform {
    #[inline]
    pub fn apply(&self, p: DVec3) -> DVec3 {
        if self.identity {
            return p;
        }
        self.rotation * p + self.translation
    }
}

/// Checks one scan descriptor and describes it; `path` names the file in
/// errors.
pub(crate) fn describe(path: &Path, index: usize, pc: &PointCloud) -> Result<ScanInfo, IoError> {
    let bad = |problem| IoError::E57 {
        path: path.to_path_buf(),
        reason: Box::new(E57Reason::Scan { index, problem }),
    };
    let pose = match &pc.transform {
        None => Pose::IDENTITY,
        Some(t) => {
            let q = &t.rotation;
            let v = &t.translation;
            pose_from([q.w, q.x, q.y, q.z], [v.x, v.y, v.z]).map_err(bad)?
        }
    };
    let (cartesian, spherical) = (pc.has_cartesian(), pc.has_spherical());
    if !cartesian && !spherical {
        return Err(bad(ScanProblem::NoCoordinates));
    }
    // With no field taking a bit, the decoder could never tell where the
    // records end (the e57 crate would fill its queues without bound).
    if pc.records > 0 && pc.prototype.iter().all(|r| bits(&r.data_type) == 0) {
        return Err(bad(ScanProblem::ZeroBitFields));
    }
    Ok(ScanInfo {
        index,
        name: pc.name.clone(),
        guid: pc.guid.clone(),
        records: pc.records,
        pose,
        posed: pc.transform.is_some(),
        cartesian,
        spherical,
        attributes: attributes(pc),
    })
}

/// Validates and normalises a pose.
fn pose_from(q: [f64; 4], t: [f64; 3]) -> Result<Pose, ScanProblem> {
    if q.iter().chain(t.iter()).any(|v| !v.is_finite()) {
        return Err(ScanProblem::PoseNotFinite {
            rotation: q,
            translation: t,
        });
    }
    let norm = q.iter().map(|v| v * v).sum::<f64>().sqrt();
    if !norm.is_finite() || norm <= 1e-12 {
        return Err(ScanProblem::RotationNotNormalisable(q));
    }
    Ok(Pose {
        rotation: q.map(|v| v / norm),
        translation: t,
    })
}

/// Bits per value of a field (as the E57 bit packing stores it).
fn bits(t: &RecordDataType) -> u32 {
    let int_bits = |min: i64, max: i64| {
        let range = i128::from(max) - i128::from(min);
        if range > 0 {
            range.ilog2() + 1
        } else {
            0
        }
    };
    match *t {
        RecordDataType::Single { .. } => 32,
        RecordDataType::Double { .. } => 64,
        RecordDataType::ScaledInteger { min, max, .. } | RecordDataType::Integer { min, max } => {
            int_bits(min, max)
        }
    }
}

/// The non-coordinate fields of a scan, by E57 name.
fn attributes(pc: &PointCloud) -> Vec<&'static str> {
    let named = [
        (RecordName::CartesianInvalidState, "cartesianInvalidState"),
        (RecordName::SphericalInvalidState, "sphericalInvalidState"),
        (RecordName::Intensity, "intensity"),
        (RecordName::ColorRed, "color"),
        (RecordName::RowIndex, "rowIndex"),
        (RecordName::ColumnIndex, "columnIndex"),
        (RecordName::ReturnIndex, "returnIndex"),
        (RecordName::ReturnCount, "returnCount"),
        (RecordName::TimeStamp, "timeStamp"),
    ];
    let mut out: Vec<&'static str> = named
        .iter()
        .filter(|(n, _)| pc.prototype.iter().any(|r| r.name == *n))
        .map(|&(_, s)| s)
        .collect();
    if pc
        .prototype
        .iter()
        .any(|r| matches!(r.name, RecordName::Unknown { .. }))
    {
        out.push("extensions");
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_pose_is_normalised_and_applied_in_f64() {
        // 90 degrees about z, quaternion given at twice unit length.
        let h = std::f64::consts::FRAC_1_SQRT_2 * 2.0;
        let pose = pose_from([h, 0.0, 0.0, h], [5.0e5, 4.0e6, 10.0]).unwrap();
        let p = pose.transform().apply(DVec3::new(1.0, 2.0, 3.0));
        let want = DVec3::new(5.0e5 - 2.0, 4.0e6 + 1.0, 13.0);
        assert!((p - want).abs().max_element() < 1e-9, "{p} vs {want}");
    }

    #[test]
    fn a_degenerate_or_non_finite_pose_is_refused() {
        assert!(pose_from([0.0; 4], [0.0; 3]).is_err());
        assert!(pose_from([1.0, 0.0, 0.0, 0.0], [f64::NAN, 0.0, 0.0]).is_err());
        assert!(pose_from([f64::INFINITY, 0.0, 0.0, 0.0], [0.0; 3]).is_err());
    }

    #[test]
    fn bits_follow_the_integer_range() {
        assert_eq!(bits(&RecordDataType::Integer { min: 0, max: 2 }), 2);
        assert_eq!(bits(&RecordDataType::Integer { min: 3, max: 3 }), 0);
        let full = RecordDataType::Integer {
            min: i64::MIN,
            max: i64::MAX,
        };
        assert_eq!(bits(&full), 64);
    }
}
