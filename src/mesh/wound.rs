//! Edges two triangles run the same way, found out of core: the triangles
//! to leave out so that a mesh whose pieces were wound separately has no
//! inconsistently wound edge. For each edge used by exactly two triangles
//! that run it in the same direction, the later of the two (by its place
//! in the stream) is named; leaving it out turns that edge into a boundary
//! edge and cannot make any other edge inconsistent (an edge's consistency
//! depends only on its own triangles). Edges of more than two triangles
//! are left to the audit: no choice of one triangle mends them.
//!
//! Each triangle gives three edge uses `(low, high, index and direction)`,
//! sorted out of core (`super::runs`); the uses of an edge then arrive
//! together. RAM: the sort's buffers and 8 bytes per triangle named.

use super::paged::Element;
use super::runs::{RunSizes, SortedRuns};
use std::io;
use std::path::Path;

/// One triangle's use of an edge: its corners low and high, the triangle's
/// place in the stream (shifted left one bit) and whether it runs the edge
/// from low to high (the bit). Ordered by edge, then triangle.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord)]
struct EdgeUse {
    low: u32,
    high: u32,
    triangle_and_forward: u64,
}

impl Element for EdgeUse {
    const BYTES: usize = 16;
    fn load(bytes: &[u8]) -> Self {
        let mut word = [0u8; 8];
        word.copy_from_slice(&bytes[8..16]);
        EdgeUse {
            low: u32::load(bytes),
            high: u32::load(&bytes[4..]),
            triangle_and_forward: u64::from_le_bytes(word),
        }
    }
    fn store(&self, bytes: &mut [u8]) {
        self.low.store(bytes);
        self.high.store(&mut bytes[4..]);
        bytes[8..16].copy_from_slice(&self.triangle_and_forward.to_le_bytes());
    }
}

/// Gathers a stream of triangles and names, at the end, the ones to leave
/// out (see the module doc).
pub(crate) struct SameWay {
    uses: SortedRuns<EdgeUse>,
    triangles: u64,
}

impl SameWay {
    /// Scratch files go beside `path`.
    pub fn new(path: &Path, sizes: RunSizes) -> Self {
        SameWay {
            uses: SortedRuns::new(path, sizes),
            triangles: 0,
        }
    }

    /// The next triangle of the stream, as it will be written.
    pub fn add(&mut self, t: [u32; 3]) -> io::Result<()> {
        let index = self.triangles;
        self.triangles += 1;
        for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            if a == b {
                continue;
            }
            self.uses.push(EdgeUse {
                low: a.min(b),
                high: a.max(b),
                triangle_and_forward: index << 1 | u64::from(a < b),
            })?;
        }
        Ok(())
    }

    /// The places of the triangles to leave out, increasing, each once.
    pub fn left_out(self) -> io::Result<Vec<u64>> {
        let mut out = Vec::new();
        let mut edge: Vec<EdgeUse> = Vec::with_capacity(3);
        let judge = |edge: &[EdgeUse], out: &mut Vec<u64>| {
            if let [a, b] = edge {
                if (a.triangle_and_forward ^ b.triangle_and_forward) & 1 == 0 {
                    out.push(b.triangle_and_forward >> 1);
                }
            }
        };
        self.uses.merge(|u| {
            if edge
                .first()
                .is_some_and(|e| (e.low, e.high) != (u.low, u.high))
            {
                judge(&edge, &mut out);
                edge.clear();
            }
            // An edge of thousands of triangles is judged by its count
            // alone: keep no more than three of its uses.
            if edge.len() < 3 {
                edge.push(u);
            }
            Ok(())
        })?;
        judge(&edge, &mut out);
        out.sort_unstable();
        out.dedup();
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::audit_mesh::audit_mesh;
    use crate::mesh::shapes::icosphere;
    use crate::mesh::Mesh;
    use crate::rng::Rng;

    fn left_out(tris: &[[u32; 3]], sizes: RunSizes) -> Vec<u64> {
        let dir = tempfile::tempdir().unwrap();
        let mut same = SameWay::new(&dir.path().join("m.ply"), sizes);
        for &t in tris {
            same.add(t).unwrap();
        }
        same.left_out().unwrap()
    }

    #[test]
    fn leaving_out_the_named_triangles_leaves_no_inconsistent_edge() {
        let tiny = RunSizes {
            chunk_bytes: 16 * 5,
            fan_in: 3,
            merge_bytes: 64,
        };
        let sphere = icosphere(3);
        let mut rng = Rng::new(9);
        for _ in 0..5 {
            // Flip a random tenth of the triangles: whole pieces wound
            // apart, as a stitch of separately wound pieces can leave them.
            let mut tris = sphere.triangles.clone();
            for t in tris.iter_mut() {
                if rng.below(10) == 0 {
                    t.swap(1, 2);
                }
            }
            let named = left_out(&tris, tiny);
            assert_eq!(named, left_out(&tris, RunSizes::DEFAULT));
            let kept: Vec<[u32; 3]> = tris
                .iter()
                .enumerate()
                .filter(|(i, _)| named.binary_search(&(*i as u64)).is_err())
                .map(|(_, &t)| t)
                .collect();
            let dir = tempfile::tempdir().unwrap();
            let before = Mesh::new(sphere.vertices.clone(), tris.clone());
            let after = Mesh::new(sphere.vertices.clone(), kept);
            let (before, after) = (
                audit_mesh(&before, dir.path()).unwrap(),
                audit_mesh(&after, dir.path()).unwrap(),
            );
            assert!(before.inconsistent_edges > 0);
            assert!(named.len() as u64 <= before.inconsistent_edges);
            assert_eq!(after.inconsistent_edges, 0);
            assert_eq!(after.non_manifold_edges, 0);
        }
        assert!(left_out(&sphere.triangles, tiny).is_empty());
    }
}
