//! Triangle meshes: the plain [`Mesh`] type and its validation, quality and
//! topology metrics (`quality`), smallest angles ([`angles`]),
//! self-intersecting pairs (`self_intersect`), distances to a reference ([`distance`]),
//! all of them for a mesh file and a reference file ([`evaluate`]),
//! streaming PLY/OBJ output (`write`), the audit of every mesh written
//! (`audit`: its topology and volumes in bounded memory, and what a run
//! promised of it) and procedural shapes for tests and benches ([`shapes`]).
//!
//! Mesh evaluation is not part of the five papers; the metrics follow the
//! standard definitions named in each module (Euler characteristic, fans,
//! Ericson's closest point). The "spacing" used to scale distances is the one
//! of `/work/shared/papers/README.md` (conventions): the mean
//! nearest-neighbour distance.

pub mod angles;
pub(crate) mod audit;
pub(crate) mod audit_mesh;
pub mod distance;
pub(crate) mod error;
pub mod evaluate;
pub(crate) mod fans;
pub(crate) mod paged;
pub(crate) mod pieces;
pub(crate) mod quality;
pub(crate) mod runs;
pub(crate) mod scratch;
pub(crate) mod self_intersect;
pub mod shapes;
pub(crate) mod untwist;
pub(crate) mod wound;
pub(crate) mod write;

mod bvh;
pub(crate) mod clearance;
pub(crate) mod closest;
pub(crate) mod intersect;
mod nearest;
mod sampling;
mod topology;
pub(crate) mod union_find;

/// Unnamed scratch beside a mesh output per triangle while it is written,
/// for the disk plan: the writer's face spool (13 B, `write`) and the
/// audit's ([`audit::SCRATCH_PER_TRIANGLE`]). Measured on the 1M noisy
/// dragon (the volume's use while it ran, less the files one can see):
/// 63 B a triangle at the peak.
pub(crate) const SCRATCH_BESIDE_OUTPUT_PER_TRIANGLE: f64 = 13.0 + audit::SCRATCH_PER_TRIANGLE;

pub use angles::{angle_report, AngleReport};
pub use audit::{incomplete_path, Failure, MeshAudit, Promise};
pub use audit_mesh::audit_mesh;
pub use distance::{
    compare, compare_with, point_to_mesh_distances, CompareOptions, DistanceReport, Reference,
};
pub use error::MeshError;
pub use pieces::{PieceFilter, PieceReport};
pub use quality::{quality, ComponentQuality, QualityReport};
pub use self_intersect::{self_intersections, SelfIntersectionReport};
pub use write::{write_mesh, MeshFormat, MeshWriter, WriteOptions, Written};

use error::non_finite_coordinate;
use glam::DVec3;

/// An indexed triangle mesh: plain data, no invariants enforced on
/// construction. Call [`Mesh::validate`] at a trust boundary; the metrics
/// below tolerate invalid data (they skip and count it) rather than panic.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions.
    pub vertices: Vec<DVec3>,
    /// Triangles as three indices into `vertices`; the order of the corners sets the orientation.
    pub triangles: Vec<[u32; 3]>,
}

impl Mesh {
    /// The mesh of `vertices` and `triangles` (not validated).
    pub fn new(vertices: Vec<DVec3>, triangles: Vec<[u32; 3]>) -> Self {
        Mesh {
            vertices,
            triangles,
        }
    }

    /// Checks that every coordinate is finite and every index is in range;
    /// reports the first offender.
    pub fn validate(&self) -> Result<(), MeshError> {
        for (i, p) in self.vertices.iter().enumerate() {
            if let Some(value) = non_finite_coordinate(*p) {
                return Err(MeshError::NonFiniteVertex {
                    vertex: i as u64,
                    value,
                });
            }
        }
        let n = self.vertices.len();
        for (t, tri) in self.triangles.iter().enumerate() {
            if let Some(&index) = tri.iter().find(|&&i| i as usize >= n) {
                return Err(MeshError::IndexOutOfRange {
                    triangle: t as u64,
                    index,
                    vertex_count: n as u64,
                });
            }
        }
        Ok(())
    }

    /// The corner positions of `tri`, or `None` when an index is out of
    /// range or a corner is not finite.
    pub fn corners(&self, tri: [u32; 3]) -> Option<[DVec3; 3]> {
        let get = |i: u32| {
            self.vertices
                .get(i as usize)
                .copied()
                .filter(|p| p.is_finite())
        };
        Some([get(tri[0])?, get(tri[1])?, get(tri[2])?])
    }

    /// Sum of triangle areas, skipping invalid triangles. Summed in fixed
    /// order, so the result is reproducible.
    pub fn area(&self) -> f64 {
        self.triangles
            .iter()
            .filter_map(|&t| self.corners(t))
            .map(|[a, b, c]| triangle_area(a, b, c))
            .sum()
    }
}

/// Six times the signed volume of the tetrahedron of triangle `t` (indices
/// into `points`) and `o`: summed over a closed surface, six times its
/// volume, positive when wound outward, whatever `o`.
pub(crate) fn volume6(points: &[DVec3], t: [u32; 3], o: DVec3) -> f64 {
    let [a, b, c] = t.map(|i| points[i as usize] - o);
    a.dot(b.cross(c))
}

/// Area of the triangle `abc`.
pub(crate) fn triangle_area(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    0.5 * (b - a).cross(c - a).length()
}
