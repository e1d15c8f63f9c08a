//! Spanning forests over Riemannian-graph edges (paper 1 section 2.4, edge
//! cost `1 - |n_i . n_j|`).
//!
//! Deviation from the paper, for tiling: instead of walking the tree with
//! Prim's algorithm from the root, each tile keeps the minimum spanning forest
//! of its own edges (Kruskal), and one global Kruskal pass over the union of
//! the tiles' forests finds the same tree (cycle property; ties broken by
//! point ids make the tree unique). The flip of each point relative to the
//! root is the parity of its tree path, as Prim's walk would set it.

use super::unionfind::ParityUnionFind;
use rayon::slice::ParallelSliceMut;

/// A Riemannian-graph edge between two points (input-order ids, `a < b`).
/// `w` is the cost `1 - |n_a . n_b|` carrying the sign of `n_a . n_b`, so a
/// negative `w` means "flip one of the two".
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Edge {
    pub w: f64,
    pub a: u32,
    pub b: u32,
}

impl Edge {
    /// The paper's edge: cost `1 - |n_a . n_b|`.
    pub fn new(a: u32, b: u32, dot: f64) -> Self {
        Edge::with_cost(a, b, 1.0 - dot.abs(), dot)
    }

    /// An edge of any non-negative cost; `dot` only gives the flip sign.
    pub fn with_cost(a: u32, b: u32, cost: f64, dot: f64) -> Self {
        let w = cost.max(0.0).copysign(dot);
        let (a, b) = if a < b { (a, b) } else { (b, a) };
        Edge { w, a, b }
    }

    /// Total order used everywhere: cost, then the two ids.
    pub fn key(&self) -> (u64, u32, u32) {
        (self.w.abs().to_bits(), self.a, self.b)
    }

    pub fn flips(&self) -> bool {
        self.w.is_sign_negative()
    }

    pub const BYTES: usize = 16;

    pub fn to_bytes(self) -> [u8; 16] {
        let mut out = [0u8; 16];
        out[..8].copy_from_slice(&self.w.to_le_bytes());
        out[8..12].copy_from_slice(&self.a.to_le_bytes());
        out[12..].copy_from_slice(&self.b.to_le_bytes());
        out
    }

    pub fn from_bytes(b: &[u8; 16]) -> Self {
        let mut w = [0u8; 8];
        w.copy_from_slice(&b[..8]);
        let a = u32::from_le_bytes([b[8], b[9], b[10], b[11]]);
        let bb = u32::from_le_bytes([b[12], b[13], b[14], b[15]]);
        Edge {
            w: f64::from_le_bytes(w),
            a,
            b: bb,
        }
    }
}

/// An edge with its endpoints' dense local numbers (`0..n` in a tile).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LocalEdge {
    pub edge: Edge,
    pub local: [u32; 2],
}

/// Minimum spanning forest of `edges` over `n` local vertices: sorts by
/// [`Edge::key`], drops repeats, and returns the forest edges in that order.
pub fn spanning_forest(mut edges: Vec<LocalEdge>, n: usize) -> Vec<Edge> {
    edges.par_sort_unstable_by_key(|e| e.edge.key());
    edges.dedup_by_key(|e| (e.edge.a, e.edge.b));
    let mut uf = ParityUnionFind::new(n);
    edges
        .into_iter()
        .filter(|e| uf.union(e.local[0], e.local[1], false))
        .map(|e| e.edge)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn edge_sign_and_bytes_round_trip() {
        let e = Edge::new(7, 3, -0.9);
        assert_eq!((e.a, e.b), (3, 7));
        assert!(e.flips());
        assert!((e.w.abs() - 0.1).abs() < 1e-12);
        assert_eq!(Edge::from_bytes(&e.to_bytes()), e);
        assert!(Edge::new(1, 2, -1.0).flips());
        assert!(!Edge::new(1, 2, 1.0).flips());
    }

    #[test]
    fn forest_keeps_cheapest_edges() {
        // Square 0-1-2-3 with one diagonal; the heaviest cycle edges go.
        let edges = [
            (0, 1, 0.9),
            (1, 2, 0.99),
            (2, 3, 0.8),
            (3, 0, 0.95),
            (0, 2, 0.5),
        ]
        .map(|(a, b, d)| LocalEdge {
            edge: Edge::new(a, b, d),
            local: [a, b],
        })
        .to_vec();
        let edges = spanning_forest(edges, 4);
        assert_eq!(edges.len(), 3);
        let kept: Vec<_> = edges.iter().map(|e| (e.a, e.b)).collect();
        assert_eq!(kept, vec![(1, 2), (0, 3), (0, 1)]);
    }
}
