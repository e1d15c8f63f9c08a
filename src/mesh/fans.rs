//! Edges of more than two triangles, found out of core: which triangles to
//! leave out so that every edge of the mesh has at most two. Of an edge's
//! triangles the two kept are those that continue each other most nearly
//! flat across it (their apexes most nearly opposite round the edge);
//! ties go to the apexes' coordinates, so the choice is the same whatever
//! order the triangles arrive in. Leaving a triangle out cannot make
//! another edge non-manifold; it may open a hole (each left out triangle
//! is counted by the caller).
//!
//! Each triangle gives three edge uses `(low, high, triangle, apex, tag,
//! direction)`, sorted out of core (`super::runs`); the uses of an edge
//! then arrive together, and every edge that two triangles share (after
//! the mending, its two kept) is handed to the caller as a [`Twin`]: the
//! dual edges of the mesh, for its winding (`super::untwist`). RAM: the
//! sort's buffers, the uses of one edge, and 8 bytes per triangle named.

use super::paged::Element;
use super::runs::{RunSizes, SortedRuns};
use glam::DVec3;
use std::io;
use std::path::Path;

/// One triangle's use of an edge, ordered by edge, then triangle.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord)]
struct FanUse {
    low: u32,
    high: u32,
    /// The triangle's place in the stream, shifted left one bit, and
    /// whether it runs the edge from low to high (the bit).
    triangle_and_forward: u64,
    apex: u32,
    /// The caller's word about the triangle.
    tag: u32,
}

/// One triangle's use of an edge two triangles share.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct EdgeUse {
    /// The triangle's place in the stream.
    pub triangle: u64,
    /// Whether it runs the edge from its lower vertex to its higher.
    pub forward: bool,
    /// Its corner off the edge.
    pub apex: u32,
    /// What the caller said of the triangle ([`Fans::add`]).
    pub tag: u32,
}

impl From<FanUse> for EdgeUse {
    fn from(u: FanUse) -> Self {
        EdgeUse {
            triangle: u.triangle_and_forward >> 1,
            forward: u.triangle_and_forward & 1 == 1,
            apex: u.apex,
            tag: u.tag,
        }
    }
}

/// An edge two triangles share: a dual edge of the mesh.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Twin {
    /// The edge's vertices, lower first.
    pub low: u32,
    pub high: u32,
    /// Its two triangles, in stream order.
    pub uses: [EdgeUse; 2],
}

impl Twin {
    /// Whether the two triangles run the edge the same way (then one of
    /// them must be turned over for the edge to be wound consistently).
    pub fn same_way(&self) -> bool {
        self.uses[0].forward == self.uses[1].forward
    }
}

impl Element for FanUse {
    const BYTES: usize = 24;
    fn load(bytes: &[u8]) -> Self {
        let mut word = [0u8; 8];
        word.copy_from_slice(&bytes[8..16]);
        FanUse {
            low: u32::load(bytes),
            high: u32::load(&bytes[4..]),
            triangle_and_forward: u64::from_le_bytes(word),
            apex: u32::load(&bytes[16..]),
            tag: u32::load(&bytes[20..]),
        }
    }
    fn store(&self, bytes: &mut [u8]) {
        self.low.store(bytes);
        self.high.store(&mut bytes[4..]);
        bytes[8..16].copy_from_slice(&self.triangle_and_forward.to_le_bytes());
        self.apex.store(&mut bytes[16..]);
        self.tag.store(&mut bytes[20..]);
    }
}

/// What became of the edges of more than two triangles.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct Mended {
    /// Places of the triangles left out, increasing, each once.
    pub left_out: Vec<u64>,
    /// Edges that had more than two triangles.
    pub edges: u64,
}

/// Gathers a stream of triangles (with a tag each) and names, at the end,
/// the ones to leave out and the edges two triangles share (see the module
/// doc).
pub(crate) struct Fans {
    uses: SortedRuns<FanUse>,
    triangles: u64,
}

impl Fans {
    /// Scratch files go beside `path`.
    pub fn new(path: &Path, sizes: RunSizes) -> Self {
        Fans {
            uses: SortedRuns::new(path, sizes),
            triangles: 0,
        }
    }

    /// The next triangle of the stream, and the caller's word about it.
    pub fn add(&mut self, t: [u32; 3], tag: u32) -> io::Result<()> {
        let index = self.triangles;
        self.triangles += 1;
        for k in 0..3 {
            let (a, b, apex) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
            if a == b {
                continue;
            }
            self.uses.push(FanUse {
                low: a.min(b),
                high: a.max(b),
                triangle_and_forward: index << 1 | u64::from(a < b),
                apex,
                tag,
            })?;
        }
        Ok(())
    }

    /// The triangles to leave out; every edge two triangles share, or
    /// the two kept of a mended edge, goes to `twin` in edge order (a
    /// triangle it names may be left out at another edge: the caller
    /// checks against `left_out`). `at` gives a vertex's coordinates
    /// (asked only round the edges mended).
    pub fn mend(
        self,
        mut at: impl FnMut(u32) -> io::Result<DVec3>,
        mut twin: impl FnMut(Twin) -> io::Result<()>,
    ) -> io::Result<Mended> {
        let mut mended = Mended::default();
        let mut edge: Vec<FanUse> = Vec::new();
        let mut judge = |edge: &[FanUse], mended: &mut Mended| -> io::Result<()> {
            let (i, j) = match edge.len() {
                0 | 1 => return Ok(()),
                2 => (0, 1),
                _ => {
                    mended.edges += 1;
                    let (i, j) = flattest_pair(edge, &mut at)?;
                    for (k, u) in edge.iter().enumerate() {
                        if k != i && k != j {
                            mended.left_out.push(u.triangle_and_forward >> 1);
                        }
                    }
                    (i, j)
                }
            };
            twin(Twin {
                low: edge[i].low,
                high: edge[i].high,
                uses: [edge[i].into(), edge[j].into()],
            })
        };
        self.uses.merge(|u| {
            if edge
                .first()
                .is_some_and(|e| (e.low, e.high) != (u.low, u.high))
            {
                judge(&edge, &mut mended)?;
                edge.clear();
            }
            edge.push(u);
            Ok(())
        })?;
        judge(&edge, &mut mended)?;
        mended.left_out.sort_unstable();
        mended.left_out.dedup();
        Ok(mended)
    }
}

/// The two uses of one edge whose apexes lie most nearly opposite round
/// it; ties to the smaller apex coordinates (lexicographic).
fn flattest_pair(
    edge: &[FanUse],
    at: &mut impl FnMut(u32) -> io::Result<DVec3>,
) -> io::Result<(usize, usize)> {
    let (a, b) = (at(edge[0].low)?, at(edge[0].high)?);
    let axis = (b - a).normalize_or_zero();
    let mut apex = Vec::with_capacity(edge.len());
    for u in edge {
        let c = at(u.apex)?;
        let off = c - a;
        apex.push(((off - axis * off.dot(axis)).normalize_or_zero(), c));
    }
    let mut best: Option<(f64, [f64; 6], (usize, usize))> = None;
    for i in 0..edge.len() {
        for j in i + 1..edge.len() {
            let score = apex[i].0.dot(apex[j].0);
            let (ci, cj) = (apex[i].1.to_array(), apex[j].1.to_array());
            let (lo, hi) = if ci <= cj { (ci, cj) } else { (cj, ci) };
            let tie = [lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]];
            let better = best.is_none_or(|(s, t, _)| score < s || (score == s && tie < t));
            if better {
                best = Some((score, tie, (i, j)));
            }
        }
    }
    Ok(best.map_or((0, 1), |b| b.2))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{quality, Mesh};

    /// Three triangles on one edge, in any order: the two that continue
    /// each other flat stay, the fin goes; a triangle elsewhere is kept.
    #[test]
    fn a_fin_on_a_flat_edge_is_left_out_whatever_the_order() {
        let points = [
            DVec3::new(0., 0., 0.),
            DVec3::new(1., 0., 0.),
            DVec3::new(0.5, 1., 0.),
            DVec3::new(0.5, -1., 0.),
            DVec3::new(0.5, 0.3, 1.),
            DVec3::new(2., 0., 0.),
        ];
        let tris = [[0, 1, 2], [1, 0, 3], [0, 1, 4], [1, 5, 2]];
        let orders: [[usize; 4]; 3] = [[0, 1, 2, 3], [2, 3, 0, 1], [3, 2, 1, 0]];
        for order in orders {
            let dir = tempfile::tempdir().unwrap();
            let mut fans = Fans::new(&dir.path().join("m.ply"), RunSizes::DEFAULT);
            for (c, &t) in order.iter().enumerate() {
                fans.add(tris[t], c as u32).unwrap();
            }
            let mut twins = Vec::new();
            let mended = fans
                .mend(
                    |v| Ok(points[v as usize]),
                    |t| {
                        twins.push(t);
                        Ok(())
                    },
                )
                .unwrap();
            let fin = order.iter().position(|&t| t == 2).unwrap() as u64;
            assert_eq!(mended.left_out, vec![fin], "{order:?}");
            assert_eq!(mended.edges, 1);
            // The mended edge's two kept run it oppositely (no turn
            // needed), and the edge 1-2 is shared by [0, 1, 2] and
            // [1, 5, 2], which run it oppositely too.
            let at = |t: usize| order.iter().position(|&o| o == t).unwrap() as u64;
            let mended_edge = twins.iter().find(|t| (t.low, t.high) == (0, 1)).unwrap();
            let kept = mended_edge.uses.map(|u| u.triangle);
            assert!(kept.contains(&at(0)) && kept.contains(&at(1)), "{twins:?}");
            assert!(!mended_edge.same_way());
            let side = twins.iter().find(|t| (t.low, t.high) == (1, 2)).unwrap();
            assert!(!side.same_way());
            assert_eq!(side.uses.map(|u| u.triangle), {
                let mut pair = [at(0), at(3)];
                pair.sort_unstable();
                pair
            });
            assert_eq!(twins.len(), 2, "{twins:?}");
            let kept: Vec<[u32; 3]> = order
                .iter()
                .enumerate()
                .filter(|(k, _)| *k as u64 != fin)
                .map(|(_, &t)| tris[t])
                .collect();
            let mesh = Mesh::new(points.to_vec(), kept);
            assert_eq!(quality(&mesh).non_manifold_edges, 0);
        }
    }
}
