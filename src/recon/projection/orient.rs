//! Settling the orientation pieces (paper 2 section 2.6 extended): every
//! triangle is rewound into its piece root's frame, and each root is
//! flipped so that its signed volume is positive: outward normals for a
//! closed surface; for an open one (terrain, seen from above with the
//! reference below it) the side facing away from the reference.
//!
//! The signed volume of a set of triangles about a point `o` is
//! `sum det(a - o, b - o, c - o) / 6`; for a closed surface it does not
//! depend on `o`.

use super::surface::Surface;
use glam::DVec3;

use crate::mesh::volume6;

/// Reverses the winding of `t`.
pub fn flipped(t: [u32; 3]) -> [u32; 3] {
    [t[0], t[2], t[1]]
}

/// The surface's triangles, each wound consistently with its root's frame
/// and every root turned to a positive volume about `reference`.
pub fn settle(surface: &mut Surface, points: &[DVec3], reference: DVec3) -> Vec<[u32; 3]> {
    let n = surface.tris.len();
    let mut roots = Vec::with_capacity(n);
    let mut volume = std::collections::BTreeMap::<u32, f64>::new();
    for tri in 0..n as u32 {
        let (root, flip) = surface.orientation(tri);
        let t = surface.tris[tri as usize];
        let t = if flip { flipped(t) } else { t };
        *volume.entry(root).or_insert(0.0) += volume6(points, t, reference);
        roots.push((root, t));
    }
    roots
        .into_iter()
        .map(|(root, t)| {
            if volume.get(&root).is_some_and(|&v| v < 0.0) {
                flipped(t)
            } else {
                t
            }
        })
        .collect()
}
