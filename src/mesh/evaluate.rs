//! What `scanmesh eval` reports of a mesh file: its quality, smallest
//! angles and self-intersecting pairs, and its distance to a reference
//! file (a mesh, or a point file whose points a selection picks).

use super::distance::{compare, DistanceReport, Reference};
use super::{
    angle_report, quality, self_intersections, AngleReport, Mesh, MeshError, QualityReport,
    SelfIntersectionReport,
};
use crate::io::{open_reader, read_all_xyz, read_mesh_any, InvalidPolicy, ReadOptions, Selection};
use std::fmt;
use std::path::Path;

/// The reports of one mesh, and its distance to a reference if one was given.
#[derive(Clone, Debug)]
pub struct Evaluation {
    /// Topology and triangle quality.
    pub quality: QualityReport,
    /// Smallest angles.
    pub angles: AngleReport,
    /// Self-intersecting triangle pairs.
    pub self_intersections: SelfIntersectionReport,
    /// Distances to the reference, both ways.
    pub distance: Option<DistanceReport>,
}

impl Evaluation {
    /// Reads the mesh at `mesh` (PLY or OBJ), checks it and measures it,
    /// then compares it with `reference` if given: a mesh, or else a point
    /// file read whole, its points those `select` picks (a selection given
    /// for a mesh reference is refused).
    pub fn of(
        mesh: &Path,
        reference: Option<&Path>,
        select: &Selection,
    ) -> Result<Self, MeshError> {
        let (vertices, triangles) = read_mesh_any(mesh)?;
        let mesh = Mesh::new(vertices, triangles);
        mesh.validate()?;
        Ok(Evaluation {
            quality: quality(&mesh),
            angles: angle_report(&mesh),
            self_intersections: self_intersections(&mesh),
            distance: match reference {
                Some(r) => Some(compare_to_file(&mesh, r, select)?),
                None => None,
            },
        })
    }

    /// The reports as one JSON object (`quality`, `angles`,
    /// `self_intersections`, `distance`: null without a reference).
    pub fn json(&self) -> serde_json::Value {
        serde_json::json!({
            "quality": self.quality,
            "angles": self.angles,
            "self_intersections": self.self_intersections,
            "distance": self.distance
        })
    }
}

/// The reports as text, one after the other.
impl fmt::Display for Evaluation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}\n{}\n{}",
            self.quality, self.angles, self.self_intersections
        )?;
        match &self.distance {
            Some(d) => write!(f, "\n{d}"),
            None => Ok(()),
        }
    }
}

/// `mesh` against the file at `reference`: a mesh, or the points of a
/// point file that `select` picks.
fn compare_to_file(
    mesh: &Mesh,
    reference: &Path,
    select: &Selection,
) -> Result<DistanceReport, MeshError> {
    let (vertices, triangles) = match read_mesh_any(reference) {
        Ok(m) if select.is_all() => m,
        Ok(_) => {
            return Err(MeshError::SelectionOfAMesh {
                path: reference.to_path_buf(),
            })
        }
        Err(_) => {
            let read = ReadOptions {
                select: select.clone(),
                ..ReadOptions::from(InvalidPolicy::Reject)
            };
            (
                read_all_xyz(open_reader(reference, read)?.as_mut())?,
                Vec::new(),
            )
        }
    };
    Ok(if triangles.is_empty() {
        compare(mesh, Reference::Points(&vertices))
    } else {
        compare(mesh, Reference::Mesh(&Mesh::new(vertices, triangles)))
    })
}
