//! Self-intersecting triangle pairs of a mesh (`scanmesh eval`): every pair
//! whose bounding boxes meet (found with the evaluation BVH, `bvh.rs`) is
//! decided exactly by `intersect.rs`, pairs sharing vertices by what they
//! share. Each pair is counted once (from its lower triangle index).
//!
//! Left out, and counted apart: invalid triangles (index out of range,
//! non-finite corner) and flat ones (repeated index or collinear corners),
//! which have no plane; the quality report counts those as degenerate.
//! Vertices are compared by index: two indices at one position are two
//! vertices, so an unwelded mesh reports its seams (weld it first).

use super::bvh::{Bvh, Primitive};
use super::closest::point_triangle_distance2;
use super::intersect::{is_flat, triangles_intersect};
use super::Mesh;
use glam::DVec3;
use rayon::prelude::*;
use std::fmt;

/// Pairs listed in the report, lowest first, to find them in a viewer.
pub const LISTED_PAIRS: usize = 10;

/// Pairs of triangles that cross each other (sharing no vertex), counted and the lowest listed.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct SelfIntersectionReport {
    /// Triangles taken into the test.
    pub triangles_tested: u64,
    /// Invalid or flat triangles left out.
    pub triangles_skipped: u64,
    /// Intersecting pairs.
    pub pairs: u64,
    /// Triangles in at least one intersecting pair.
    pub triangles_involved: u64,
    /// The first `LISTED_PAIRS` pairs (triangle indices, lower first),
    /// in order.
    pub first_pairs: Vec<[u32; 2]>,
}

/// A triangle with its vertex indices, stored in leaf order.
struct Indexed {
    corners: [DVec3; 3],
    vertices: [u32; 3],
}

impl Primitive for Indexed {
    fn bounds(&self) -> (DVec3, DVec3) {
        let [a, b, c] = self.corners;
        (a.min(b).min(c), a.max(b).max(c))
    }
    fn distance2(&self, p: DVec3) -> f64 {
        let [a, b, c] = self.corners;
        point_triangle_distance2(p, a, b, c)
    }
}

/// Counts the self-intersecting pairs of `mesh`. Deterministic (integer
/// counts, pairs sorted). Memory: about 100 B per tested triangle.
pub fn self_intersections(mesh: &Mesh) -> SelfIntersectionReport {
    let usable = |t: [u32; 3]| mesh.corners(t).filter(|c| !is_flat(c));
    // Beyond u32::MAX triangles the tree's ids overflow; no mesh with u32
    // vertex indices that fits in memory gets there.
    let ids: Vec<u32> = (0..mesh.triangles.len().min(u32::MAX as usize) as u32)
        .into_par_iter()
        .filter(|&t| usable(mesh.triangles[t as usize]).is_some())
        .collect();
    let make = |i: u32| {
        let t = mesh.triangles[ids[i as usize] as usize];
        Indexed {
            // Every id passed the `usable` check above.
            corners: mesh.corners(t).unwrap_or([DVec3::NAN; 3]),
            vertices: t,
        }
    };
    let bvh = Bvh::build(ids.len(), |i| make(i).bounds(), make);
    let mut pairs: Vec<[u32; 2]> = (0..ids.len() as u32)
        .into_par_iter()
        .flat_map_iter(|i| {
            let me = make(i);
            let (lo, hi) = me.bounds();
            let mut found = Vec::new();
            bvh.for_each_overlapping(lo, hi, |j, other| {
                if j > i
                    && triangles_intersect(me.vertices, &me.corners, other.vertices, &other.corners)
                {
                    found.push([ids[i as usize], ids[j as usize]]);
                }
            });
            found
        })
        .collect();
    pairs.par_sort_unstable();
    let mut involved: Vec<u32> = pairs.iter().flatten().copied().collect();
    involved.par_sort_unstable();
    involved.dedup();
    SelfIntersectionReport {
        triangles_tested: ids.len() as u64,
        triangles_skipped: (mesh.triangles.len() - ids.len()) as u64,
        pairs: pairs.len() as u64,
        triangles_involved: involved.len() as u64,
        first_pairs: pairs.into_iter().take(LISTED_PAIRS).collect(),
    }
}

impl fmt::Display for SelfIntersectionReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "self-intersect.   {} pairs ({} triangles; {} tested, {} flat or invalid left out)",
            self.pairs, self.triangles_involved, self.triangles_tested, self.triangles_skipped
        )?;
        if !self.first_pairs.is_empty() {
            let list: Vec<String> = self
                .first_pairs
                .iter()
                .map(|[a, b]| format!("{a}/{b}"))
                .collect();
            write!(f, "; first: {}", list.join(" "))?;
        }
        Ok(())
    }
}
