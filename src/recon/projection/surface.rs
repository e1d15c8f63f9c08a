//! The mesh under construction (paper 2 section 2.3): vertex states,
//! triangles, the triangles around each vertex, and the orientation pieces.
//!
//! Invariant kept by [`Surface::try_add`]: every directed edge is used by at
//! most one triangle, in the triangles' *effective* orientation. That one
//! rule gives both properties the output promises: no edge has more than
//! two triangles (two would need the same direction twice), and the two
//! triangles of an edge traverse it in opposite directions (consistent
//! winding).
//!
//! Orientation without a Riemannian graph (section 2.6) is local, so two
//! fronts grown from different seeds may meet with opposite windings. Each
//! triangle therefore belongs to a *piece*, an element of a parity
//! union-find: its effective winding is its stored one, flipped when its
//! piece's parity to the root is odd. A triangle joining two pieces
//! records how they relate; a triangle that would contradict a relation
//! already known (an inconsistent edge, or a Moebius band closing) is
//! refused. The pieces are settled at the end (`orient.rs`).
//!
//! Storage: triangles in an array, and for each vertex a linked list of its
//! corners (4 B per corner, 4 B per vertex), its triangle count, its count
//! of open edges (edges of one triangle) and two sums over their far ends,
//! 24 B: about 52 B per vertex for a mesh of two triangles per vertex. The
//! counts answer [`Surface::is_closed`], and the sums
//! [`Surface::boundary_ends`], without walking the corners: the growth
//! asks the first after every triangle it adds, the second for every front
//! vertex it looks at (walking corners there was a tenth of the run).

use crate::normals::unionfind::ParityUnionFind;

/// "No entry" in the corner lists.
pub const NONE: u32 = u32::MAX;

/// Vertex states of section 2.3, and `Unused` for points that are never
/// vertices (left out by the thinning, or without a tangent plane).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum State {
    /// No triangle yet.
    Free,
    /// Has triangles and waits in the front to be processed.
    Fringe,
    /// Processed; its triangles do not close around it.
    Boundary,
    /// Its triangles close around it: nothing can be added.
    Completed,
    Unused,
}

/// One triangle around a vertex `v`: the triangle is `(v, a, b)` in its
/// stored order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Wedge {
    pub a: u32,
    pub b: u32,
    pub tri: u32,
}

pub struct Surface {
    pub tris: Vec<[u32; 3]>,
    /// Orientation piece of each triangle (an element of `pieces`).
    pub piece: Vec<u32>,
    /// Next corner (`3 * tri + i`) at the same vertex, or [`NONE`].
    next: Vec<u32>,
    /// First corner at each vertex, or [`NONE`].
    head: Vec<u32>,
    /// Triangles at each vertex.
    degree: Vec<u32>,
    /// Edges at each vertex that have one triangle.
    open: Vec<u32>,
    /// The far ends of those edges: their sum, and the sum of their
    /// squares (wrapping), which give the two ends of a vertex with two.
    open_sum: Vec<u64>,
    open_squares: Vec<u64>,
    pub state: Vec<State>,
    /// Pieces: pieces handed in first (`seed_base` of them), then one
    /// element per vertex (a new piece is named by its seed).
    pub pieces: ParityUnionFind,
    seed_base: u32,
}

/// Why a triangle was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Refusal {
    /// A directed edge is taken (a third triangle, or opposite windings).
    Edge,
    /// Joining the pieces would contradict an earlier relation.
    Orientation,
}

impl Surface {
    pub fn new(n: usize) -> Self {
        Self::with_pieces(n, 0)
    }

    /// A surface over `n` vertices that will also hold triangles of
    /// `given` pieces named `0..given` (the seam pass's fixed triangles).
    pub fn with_pieces(n: usize, given: u32) -> Self {
        Surface {
            tris: Vec::with_capacity(2 * n),
            piece: Vec::with_capacity(2 * n),
            next: Vec::with_capacity(6 * n),
            head: vec![NONE; n],
            degree: vec![0; n],
            open: vec![0; n],
            open_sum: vec![0; n],
            open_squares: vec![0; n],
            state: vec![State::Free; n],
            pieces: ParityUnionFind::new(given as usize + n),
            seed_base: given,
        }
    }

    /// The piece a growth seeded at `v` starts.
    pub fn seed_piece(&self, v: u32) -> u32 {
        self.seed_base + v
    }

    /// The triangles around `v`, most recent first.
    pub fn wedges(&self, v: u32) -> Wedges<'_> {
        Wedges {
            s: self,
            corner: self.head[v as usize],
        }
    }

    pub fn has_triangles(&self, v: u32) -> bool {
        self.head[v as usize] != NONE
    }

    /// Root of `tri`'s piece and whether its stored winding is flipped
    /// relative to the root.
    pub fn orientation(&mut self, tri: u32) -> (u32, bool) {
        self.pieces.find(self.piece[tri as usize])
    }

    /// Whether `tri` runs `x -> y` in its stored order.
    fn runs(&self, tri: u32, x: u32, y: u32) -> bool {
        let t = self.tris[tri as usize];
        (0..3).any(|i| t[i] == x && t[(i + 1) % 3] == y)
    }

    /// The triangles on the undirected edge `x`-`y` (at most two while the
    /// invariant holds; more are ignored).
    pub fn edge_triangles(&self, x: u32, y: u32) -> ([u32; 2], usize) {
        let mut out = [NONE; 2];
        let mut n = 0;
        for w in self.wedges(x) {
            if (w.a == y || w.b == y) && n < 2 {
                out[n] = w.tri;
                n += 1;
            }
        }
        (out, n)
    }

    /// Adds triangle `t` (stored winding as given) to the piece `piece`,
    /// whose root frame the winding is expressed in, if the invariant
    /// allows; joins the pieces it meets across its edges.
    pub fn try_add(&mut self, t: [u32; 3], piece: u32) -> Result<u32, Refusal> {
        self.try_add_on(t, piece, self.edges(t))
    }

    /// The triangles on each edge `t[i]`-`t[i + 1]` ([`Surface::edge_triangles`]).
    pub fn edges(&self, t: [u32; 3]) -> [([u32; 2], usize); 3] {
        [0, 1, 2].map(|i| self.edge_triangles(t[i], t[(i + 1) % 3]))
    }

    /// [`Surface::try_add`] with `t`'s [`Surface::edges`], found by a
    /// caller that read them for its own checks.
    pub fn try_add_on(
        &mut self,
        t: [u32; 3],
        piece: u32,
        edges: [([u32; 2], usize); 3],
    ) -> Result<u32, Refusal> {
        let (root, flip) = self.pieces.find(piece);
        // The relations this triangle imposes: (other piece, its parity to
        // the new triangle's frame).
        let mut joins: [(u32, bool); 3] = [(NONE, false); 3];
        for (i, join) in joins.iter_mut().enumerate() {
            let (x, y) = (t[i], t[(i + 1) % 3]);
            let (tris, n) = edges[i];
            match n {
                0 => {}
                1 => {
                    let other = tris[0];
                    let (r, f) = self.orientation(other);
                    // The neighbour must run y -> x in the new frame: its
                    // stored direction x -> y needs an odd relation.
                    let stored_same = self.runs(other, x, y);
                    let need = stored_same ^ f ^ flip;
                    if r == root {
                        if need {
                            return Err(Refusal::Edge);
                        }
                    } else {
                        *join = (r, need);
                    }
                }
                _ => return Err(Refusal::Edge),
            }
        }
        // Relations between pieces not yet joined must agree with each other.
        for i in 0..3 {
            for j in 0..i {
                if joins[i].0 != NONE && joins[i].0 == joins[j].0 && joins[i].1 != joins[j].1 {
                    return Err(Refusal::Orientation);
                }
            }
        }
        for &(r, need) in &joins {
            if r != NONE {
                // `need`: r's stored frame is flipped relative to `root`'s.
                self.pieces.union(r, root, need);
            }
        }
        Ok(self.append(t, piece, edges.map(|e| e.1)))
    }

    /// Appends a triangle without checks (fixed triangles handed in, which
    /// met the invariant when they were made).
    pub fn push(&mut self, t: [u32; 3], piece: u32) -> u32 {
        let shared = self.edges(t).map(|e| e.1);
        self.append(t, piece, shared)
    }

    /// Appends `t`, whose edges had `shared[i]` triangles before it.
    fn append(&mut self, t: [u32; 3], piece: u32, shared: [usize; 3]) -> u32 {
        let tri = self.tris.len() as u32;
        self.tris.push(t);
        self.piece.push(piece);
        for (i, &v) in t.iter().enumerate() {
            self.next.push(self.head[v as usize]);
            self.head[v as usize] = 3 * tri + i as u32;
            self.degree[v as usize] += 1;
        }
        for (i, &n) in shared.iter().enumerate() {
            let ends = [t[i], t[(i + 1) % 3]].map(|v| v as usize);
            match n {
                0 => {
                    self.open_end(ends[0], ends[1], true);
                    self.open_end(ends[1], ends[0], true);
                }
                1 => {
                    self.open_end(ends[0], ends[1], false);
                    self.open_end(ends[1], ends[0], false);
                }
                _ => {}
            }
        }
        tri
    }

    /// The edge `v`-`far` becomes open (`opens`) or closed at `v`.
    fn open_end(&mut self, v: usize, far: usize, opens: bool) {
        let (y, y2) = (far as u64, (far as u64).wrapping_mul(far as u64));
        if opens {
            self.open[v] += 1;
            self.open_sum[v] += y;
            self.open_squares[v] = self.open_squares[v].wrapping_add(y2);
        } else {
            self.open[v] -= 1;
            self.open_sum[v] -= y;
            self.open_squares[v] = self.open_squares[v].wrapping_sub(y2);
        }
    }

    /// The far ends of `v`'s two open edges, smaller first, when it has
    /// exactly two: from their sum `a` and sum of squares `b`, whose
    /// `2b - a^2` is the square of their difference (below 2^64, so exact
    /// in wrapping arithmetic). No corner walk.
    pub fn boundary_ends(&self, v: u32) -> Option<[u32; 2]> {
        let v = v as usize;
        if self.open[v] != 2 {
            return None;
        }
        let a = self.open_sum[v];
        let d2 = self.open_squares[v]
            .wrapping_mul(2)
            .wrapping_sub(a.wrapping_mul(a));
        let d = isqrt(d2);
        Some([((a - d) / 2) as u32, ((a + d) / 2) as u32])
    }

    /// Whether `v` has an edge with one triangle.
    pub fn has_open_edges(&self, v: u32) -> bool {
        self.open[v as usize] > 0
    }

    /// Edges at `v` with one triangle.
    pub fn open_edges(&self, v: u32) -> u32 {
        self.open[v as usize]
    }

    /// Whether the triangles around `v` close around it: at least three,
    /// and every triangle edge at `v` shared by two of them. With the
    /// directed-edge rule that is one closed fan, or, rarely, two fans
    /// pinched at `v`; either way nothing more can be added at `v`.
    pub fn is_closed(&self, v: u32) -> bool {
        let v = v as usize;
        self.open[v] == 0 && (3..=MAX_CLOSED).contains(&self.degree[v])
    }

    fn wedge_at(&self, corner: u32) -> Wedge {
        let tri = corner / 3;
        let t = self.tris[tri as usize];
        let (a, b) = match corner - 3 * tri {
            0 => (t[1], t[2]),
            1 => (t[2], t[0]),
            _ => (t[0], t[1]),
        };
        Wedge { a, b, tri }
    }
}

/// The integer square root of `x`.
fn isqrt(x: u64) -> u64 {
    let mut r = (x as f64).sqrt() as u64;
    while u128::from(r) * u128::from(r) > u128::from(x) {
        r -= 1;
    }
    while u128::from(r + 1) * u128::from(r + 1) <= u128::from(x) {
        r += 1;
    }
    r
}

/// Fans of more triangles than this are never closed (a vertex of a sane
/// surface mesh has about six): the cap the corner walk this count
/// replaced had, kept so that the output did not change.
const MAX_CLOSED: u32 = 24;

pub struct Wedges<'a> {
    s: &'a Surface,
    corner: u32,
}

impl Iterator for Wedges<'_> {
    type Item = Wedge;
    fn next(&mut self) -> Option<Wedge> {
        if self.corner == NONE {
            return None;
        }
        let w = self.s.wedge_at(self.corner);
        self.corner = self.s.next[self.corner as usize];
        Some(w)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn invariant_refuses_third_triangles_and_opposite_windings() {
        let mut s = Surface::new(6);
        let t0 = s.try_add([0, 1, 2], 0).unwrap();
        assert_eq!(t0, 0);
        // Consistent neighbour across 1-2 (runs 2 -> 1).
        assert!(s.try_add([2, 1, 3], 0).is_ok());
        // Same winding across 0-1 in the same piece: an inconsistent edge.
        assert_eq!(s.try_add([0, 1, 4], 0), Err(Refusal::Edge));
        // A third triangle on 1-2.
        assert_eq!(s.try_add([1, 5, 2], 0), Err(Refusal::Edge));
        assert_eq!(s.edge_triangles(1, 2).1, 2);
    }

    #[test]
    fn pieces_join_with_the_parity_their_shared_edge_needs() {
        let mut s = Surface::new(8);
        s.try_add([0, 1, 2], 0).unwrap();
        // Another seed's piece, wound the same way on edge 1-2: it must be
        // flipped relative to piece 0 to share the edge.
        s.try_add([1, 2, 3], 3).unwrap();
        let (r0, f0) = s.orientation(0);
        let (r1, f1) = s.orientation(1);
        assert_eq!(r0, r1);
        assert_ne!(f0, f1);
        // In piece 0's frame [1, 2, 3] is wound [3, 2, 1] and runs 3 -> 2,
        // so a triangle of piece 0 must run 2 -> 3.
        assert_eq!(s.try_add([3, 2, 4], 0), Err(Refusal::Edge));
        assert!(s.try_add([2, 3, 4], 0).is_ok());
    }

    #[test]
    fn closure_follows_the_effective_winding() {
        let mut s = Surface::new(8);
        for (i, t) in [[0, 1, 2], [0, 2, 3], [0, 3, 4]].iter().enumerate() {
            s.try_add(*t, i as u32 % 2).unwrap();
        }
        assert!(!s.is_closed(0));
        s.try_add([0, 4, 1], 0).unwrap();
        assert!(s.is_closed(0));
        assert!(!s.is_closed(1));
    }

    #[test]
    fn closure_counts_follow_pushed_and_added_triangles() {
        let mut s = Surface::new(8);
        // Two triangles on the same three vertices (a pillow): every edge
        // has two triangles, but two triangles do not close a fan.
        s.push([0, 1, 2], 0);
        s.try_add([0, 2, 1], 0).unwrap();
        assert_eq!(s.open_edges(0), 0);
        assert!(!s.is_closed(0));
        // A fan of four around 3, the first two handed in unchecked.
        let mut s = Surface::new(8);
        s.push([3, 4, 5], 0);
        s.push([3, 5, 6], 0);
        assert_eq!((s.open_edges(3), s.open_edges(5)), (2, 2));
        s.try_add([3, 6, 7], 0).unwrap();
        assert!(!s.is_closed(3));
        s.try_add([3, 7, 4], 0).unwrap();
        assert!(s.is_closed(3));
        assert_eq!(s.open_edges(4), 2);
        assert!(s.has_open_edges(7) && !s.has_open_edges(3));
        assert_eq!(s.boundary_ends(4), Some([5, 7]));
        assert_eq!(s.boundary_ends(3), None);
    }

    #[test]
    fn the_two_ends_come_back_from_their_sums_even_where_squares_wrap() {
        assert_eq!(isqrt(u64::MAX), u64::from(u32::MAX));
        assert_eq!((isqrt(15), isqrt(16), isqrt(0)), (3, 4, 0));
        for (e1, e2) in [
            (0u32, 1u32),
            (7, 7 + 1),
            (3, u32::MAX),
            (u32::MAX - 7, u32::MAX),
        ] {
            let mut s = Surface::new(1);
            s.open_end(0, e1 as usize, true);
            s.open_end(0, 12_345, true);
            s.open_end(0, e2 as usize, true);
            s.open_end(0, 12_345, false);
            assert_eq!(s.boundary_ends(0), Some([e1, e2]));
        }
    }

    #[test]
    fn boundary_ends_match_a_corner_walk_over_a_strip() {
        // A fan strip 0-1-2-...: each vertex's open edges by walking its
        // corners, against the sums.
        let mut s = Surface::new(12);
        for i in 0..10u32 {
            let t = if i % 2 == 0 {
                [i, i + 1, i + 2]
            } else {
                [i + 1, i, i + 2]
            };
            s.try_add(t, 0).unwrap();
        }
        for v in 0..12u32 {
            let mut ends: Vec<u32> = s.wedges(v).flat_map(|w| [w.a, w.b]).collect();
            ends.sort_unstable();
            let single: Vec<u32> = ends
                .iter()
                .copied()
                .filter(|e| ends.iter().filter(|x| *x == e).count() == 1)
                .collect();
            let want = (single.len() == 2).then(|| [single[0], single[1]]);
            assert_eq!(s.boundary_ends(v), want, "vertex {v}");
        }
    }
}
