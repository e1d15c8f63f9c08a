//! Exact nearest-surface and nearest-point queries for mesh evaluation, on
//! the bounding-volume hierarchy of `bvh.rs`. Private to the mesh module on
//! purpose: the project's kNN module serves tiles of scans; evaluation only
//! needs "distance to the nearest", "nearest other point" included.
//!
//! Memory: a triangle index holds each valid triangle's corners (72 B), its
//! id (4 B) and about 19 B of nodes: ~95 B per triangle (measured peak
//! while building, 10M triangles: 102 B). A point index: ~47 B per point.

use super::bvh::{Bvh, Primitive};
use super::closest::point_triangle_distance2;
use super::Mesh;
use glam::DVec3;

/// A triangle stored by value: leaves scan contiguous corners instead of
/// chasing indices into the vertex array.
struct Triangle([DVec3; 3]);

impl Primitive for Triangle {
    fn bounds(&self) -> (DVec3, DVec3) {
        let [a, b, c] = self.0;
        (a.min(b).min(c), a.max(b).max(c))
    }
    fn distance2(&self, p: DVec3) -> f64 {
        let [a, b, c] = self.0;
        point_triangle_distance2(p, a, b, c)
    }
}

/// The valid triangles of a mesh (in range, finite).
pub(crate) struct TriangleIndex {
    bvh: Bvh<Triangle>,
}

impl TriangleIndex {
    pub fn new(mesh: &Mesh) -> Self {
        // Beyond u32::MAX triangles the tree's ids would overflow; no mesh
        // with u32 vertex indices that fits in memory gets there.
        let ids: Vec<u32> = (0..mesh.triangles.len().min(u32::MAX as usize) as u32)
            .filter(|&t| mesh.corners(mesh.triangles[t as usize]).is_some())
            .collect();
        let corners = |i: u32| {
            let t = mesh.triangles[ids[i as usize] as usize];
            // Every id passed the `corners` check above.
            mesh.corners(t).unwrap_or([DVec3::NAN; 3])
        };
        TriangleIndex {
            bvh: Bvh::build(
                ids.len(),
                |i| Triangle(corners(i)).bounds(),
                |i| Triangle(corners(i)),
            ),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.bvh.len() == 0
    }

    /// Distance from `p` to the nearest triangle: infinite when there is
    /// none, NaN for a non-finite `p`.
    pub fn distance(&self, p: DVec3) -> f64 {
        if !p.is_finite() {
            return f64::NAN;
        }
        self.bvh.nearest_distance2(p, None).sqrt()
    }
}

/// Finite points, for nearest-point queries.
pub(crate) struct PointIndex {
    bvh: Bvh<DVec3>,
}

impl PointIndex {
    /// Indexes `points`, which the caller has filtered to finite ones
    /// (at most u32::MAX are indexed).
    pub fn new(points: &[DVec3]) -> Self {
        let ids: Vec<u32> = (0..points.len().min(u32::MAX as usize) as u32)
            .filter(|&i| points[i as usize].is_finite())
            .collect();
        let point = |i: u32| points[ids[i as usize] as usize];
        PointIndex {
            bvh: Bvh::build(ids.len(), |i| point(i).bounds(), &point),
        }
    }

    pub fn len(&self) -> usize {
        self.bvh.len()
    }

    /// Distance from `p` to the nearest indexed point (infinite if none).
    pub fn distance(&self, p: DVec3) -> f64 {
        if !p.is_finite() {
            return f64::NAN;
        }
        self.bvh.nearest_distance2(p, None).sqrt()
    }

    /// Distance from the indexed point number `i` (at `p`) to the nearest
    /// other point; a duplicate of `p` counts, at distance zero.
    pub fn neighbour_distance(&self, i: usize, p: DVec3) -> f64 {
        self.bvh.nearest_distance2(p, Some(i as u32)).sqrt()
    }
}
