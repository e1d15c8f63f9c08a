//! Edge-based topology of a triangle mesh: components, edge classes, fans
//! around vertices, boundary loops and orientation, from one sorted list of
//! half-edges (no hash maps, so the result never depends on iteration order).
//!
//! Only *topological* triangles take part: indices in range, finite corners
//! and three distinct indices. A triangle with a repeated index has no area
//! and no well-defined edges; counting its "edges" would invent boundary or
//! non-manifold edges that no cleaner would keep.
//!
//! Memory, with triangle count F, vertex count V and `u32` slots (F below
//! 1.43 billion; `u64` beyond, about 29 more bytes per triangle): half-edges
//! 36 B/F (three 12 B records), fan sets 12 B/F, orientation sets 5 B/F,
//! usable flags 1 B/F, loop marks 3 bits/F, component ids 4 B/V (plus 4 B/V
//! for the vertex sets, freed before the half-edges exist), fan counts
//! 1 B/V. Peak: about 55 B per triangle plus 5 B per vertex, beside the
//! mesh itself (12 B/F + 24 B/V).

use super::union_find::{DisjointSets, ParitySets, Slot};
use super::Mesh;
use rayon::slice::ParallelSliceMut;

/// Per-component counts, components numbered by their smallest vertex.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct ComponentCounts {
    pub first_vertex: u32,
    pub vertices: u64,
    pub triangles: u64,
    pub edges: u64,
    pub boundary_edges: u64,
    pub boundary_loops: u64,
    pub non_manifold_edges: u64,
    pub non_manifold_vertices: u64,
    pub inconsistent_edges: u64,
    /// False once an odd cycle of orientation constraints was found.
    pub orientable: bool,
}

/// One directed edge of a triangle, keyed by its undirected vertex pair.
/// Field order gives the sort order: (lo, hi, corner), a total order.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
struct HalfEdge<S> {
    lo: u32,
    hi: u32,
    /// `3 * triangle + i`: the edge runs from corner `i` to corner `i + 1`.
    corner: S,
}

/// Marker for "vertex not used by any topological triangle".
const UNREFERENCED: u32 = u32::MAX;

pub(crate) fn is_topological(mesh: &Mesh, t: [u32; 3]) -> bool {
    t[0] != t[1] && t[1] != t[2] && t[0] != t[2] && mesh.corners(t).is_some()
}

/// Topology of every connected component of `mesh`.
pub(crate) fn analyse(mesh: &Mesh) -> Vec<ComponentCounts> {
    if u32::holds(mesh.triangles.len().saturating_mul(3)) {
        Analysis::<u32>::run(mesh)
    } else {
        Analysis::<u64>::run(mesh)
    }
}

struct Analysis<'m, S: Slot> {
    mesh: &'m Mesh,
    usable: Vec<bool>,
    /// Component id of each vertex, or [`UNREFERENCED`].
    component: Vec<u32>,
    comps: Vec<ComponentCounts>,
    /// Corners (`3 * t + i`) joined when their triangles share an edge at
    /// that corner's vertex: each set is one fan.
    fans: DisjointSets<S>,
}

impl<'m, S: Slot> Analysis<'m, S> {
    fn run(mesh: &'m Mesh) -> Vec<ComponentCounts> {
        let usable: Vec<bool> = mesh
            .triangles
            .iter()
            .map(|&t| is_topological(mesh, t))
            .collect();
        let (component, comps) = if u32::holds(mesh.vertices.len()) {
            components::<u32>(mesh, &usable)
        } else {
            components::<u64>(mesh, &usable)
        };
        let mut a: Analysis<S> = Analysis {
            mesh,
            usable,
            component,
            comps,
            fans: DisjointSets::new(mesh.triangles.len() * 3),
        };
        let half_edges = a.sorted_half_edges();
        a.edge_pass(&half_edges);
        a.count_fans();
        a.count_loops(&half_edges);
        a.comps
    }

    fn sorted_half_edges(&self) -> Vec<HalfEdge<S>> {
        let usable_count = self.usable.iter().filter(|&&u| u).count();
        let mut out = Vec::with_capacity(usable_count * 3);
        for (t, tri) in self.mesh.triangles.iter().enumerate() {
            if !self.usable[t] {
                continue;
            }
            for i in 0..3 {
                let (a, b) = (tri[i], tri[(i + 1) % 3]);
                out.push(HalfEdge {
                    lo: a.min(b),
                    hi: a.max(b),
                    corner: S::from_usize(3 * t + i),
                });
            }
        }
        // Keys are unique, so an unstable sort is still deterministic.
        out.par_sort_unstable();
        out
    }

    /// The corner of `h`'s triangle at vertex `lo` (`at_lo`) or `hi`.
    fn corner_at(&self, h: &HalfEdge<S>, at_lo: bool) -> usize {
        let c = h.corner.to_usize();
        let (t, i) = (c / 3, c % 3);
        let from_is_lo = self.mesh.triangles[t][i] == h.lo;
        if from_is_lo == at_lo {
            c
        } else {
            3 * t + (i + 1) % 3
        }
    }

    /// Whether `h` runs from `lo` to `hi` in its triangle.
    fn forward(&self, h: &HalfEdge<S>) -> bool {
        let c = h.corner.to_usize();
        self.mesh.triangles[c / 3][c % 3] == h.lo
    }

    /// Classifies every undirected edge and joins the fans and orientation
    /// classes across it.
    fn edge_pass(&mut self, half_edges: &[HalfEdge<S>]) {
        let mut orientation = ParitySets::<S>::new(self.mesh.triangles.len());
        for group in half_edges.chunk_by(|a, b| (a.lo, a.hi) == (b.lo, b.hi)) {
            let ci = self.component[group[0].lo as usize] as usize;
            self.comps[ci].edges += 1;
            match group.len() {
                1 => self.comps[ci].boundary_edges += 1,
                2 => {
                    let same_direction = self.forward(&group[0]) == self.forward(&group[1]);
                    if same_direction {
                        self.comps[ci].inconsistent_edges += 1;
                    }
                    let t0 = group[0].corner.to_usize() / 3;
                    let t1 = group[1].corner.to_usize() / 3;
                    if !orientation.relate(t0, t1, same_direction) {
                        self.comps[ci].orientable = false;
                    }
                }
                _ => self.comps[ci].non_manifold_edges += 1,
            }
            for h in &group[1..] {
                for at_lo in [true, false] {
                    let (a, b) = (self.corner_at(&group[0], at_lo), self.corner_at(h, at_lo));
                    self.fans.union(a, b);
                }
            }
        }
    }

    /// A vertex whose corners form more than one fan is non-manifold (a
    /// bow-tie), whatever its edges look like.
    fn count_fans(&mut self) {
        let mut fans_at = vec![0u8; self.mesh.vertices.len()];
        for (t, tri) in self.mesh.triangles.iter().enumerate() {
            if !self.usable[t] {
                continue;
            }
            for (i, &v) in tri.iter().enumerate() {
                if self.fans.is_root(3 * t + i) {
                    let count = &mut fans_at[v as usize];
                    *count = count.saturating_add(1);
                    if *count == 2 {
                        let ci = self.component[v as usize] as usize;
                        self.comps[ci].non_manifold_vertices += 1;
                    }
                }
            }
        }
    }

    /// Boundary loops: each boundary edge joins the fan at its two ends, so
    /// the two boundary edges that close one fan end up in one loop. Loops
    /// are the resulting classes. At a bow-tie vertex each fan pairs its
    /// own edges, which is exactly the loops of the mesh with that vertex
    /// split per fan; no chaining by "next edge out of this vertex", which
    /// is ambiguous where two loops touch.
    fn count_loops(&mut self, half_edges: &[HalfEdge<S>]) {
        let boundary = || {
            half_edges
                .chunk_by(|a, b| (a.lo, a.hi) == (b.lo, b.hi))
                .filter(|g| g.len() == 1)
                .map(|g| g[0])
        };
        for h in boundary() {
            let (a, b) = (self.corner_at(&h, true), self.corner_at(&h, false));
            self.fans.union(a, b);
        }
        // One bit per corner marks the loop roots already counted.
        let mut counted = vec![0u64; self.mesh.triangles.len() * 3 / 64 + 1];
        for h in boundary() {
            let root = self.fans.find(self.corner_at(&h, true));
            let (word, bit) = (root / 64, 1u64 << (root % 64));
            if counted[word] & bit == 0 {
                counted[word] |= bit;
                let ci = self.component[h.lo as usize] as usize;
                self.comps[ci].boundary_loops += 1;
            }
        }
    }
}

/// Component id per vertex (by shared vertices of topological triangles)
/// and the per-component vertex and triangle counts.
fn components<V: Slot>(mesh: &Mesh, usable: &[bool]) -> (Vec<u32>, Vec<ComponentCounts>) {
    let n = mesh.vertices.len();
    let mut sets = DisjointSets::<V>::new(n);
    let mut component = vec![UNREFERENCED; n];
    for (t, tri) in mesh.triangles.iter().enumerate() {
        if usable[t] {
            sets.union(tri[0] as usize, tri[1] as usize);
            sets.union(tri[0] as usize, tri[2] as usize);
            for &v in tri {
                component[v as usize] = 0;
            }
        }
    }
    let mut comps: Vec<ComponentCounts> = Vec::new();
    for v in 0..n {
        if component[v] == UNREFERENCED {
            continue;
        }
        // Roots are the smallest member, so the root was numbered already.
        let root = sets.find(v);
        if root == v {
            component[v] = comps.len() as u32;
            comps.push(ComponentCounts {
                first_vertex: v as u32,
                orientable: true,
                ..Default::default()
            });
        } else {
            component[v] = component[root];
        }
        comps[component[v] as usize].vertices += 1;
    }
    for (t, tri) in mesh.triangles.iter().enumerate() {
        if usable[t] {
            comps[component[tri[0] as usize] as usize].triangles += 1;
        }
    }
    (component, comps)
}
