//! Pinched hole loops of `--closed` ([`super::holes`]): a boundary that
//! passes one vertex twice, where two wedges of triangles around the vertex
//! each bring a boundary edge in and one out. The walk along the boundary
//! must turn at such a vertex from one wedge's incoming edge to the *other*
//! wedge's outgoing edge: the patch then fills the gap between the two
//! wedges and the vertex's triangles close into one fan. Turning into the
//! same wedge's outgoing edge would close each wedge on its own, and the
//! vertex would stay where two cones touch.
//!
//! Why: the demo's dragon (issue 19) kept one hole of 70 edges through two
//! such vertices (mis-oriented normals at a thin part pinch the zero set
//! there), and the walk could not tell which way to turn.
//!
//! The wedges come from the triangles kept around boundary vertices
//! ([`super::hole_guard::NearHoles`]); a vertex whose kept triangles do not
//! split into exactly two wedges with one edge in and one out each gets no
//! turn, and its loop is left open as before. Left out: a vertex with more
//! than two wedges (the turns would have to join all wedges in one cycle,
//! which needs their order around the vertex).

use std::collections::HashMap;

/// The turn the boundary walk takes at each pinch vertex it can resolve:
/// `(from, at) -> to` for the boundary edges `from -> at -> to`.
/// `edges` are the directed boundary edges; `triangles_at(v)` the mesh
/// triangles around `v` (wound like the mesh, repeats allowed).
pub fn turns(
    pinches: &[u32],
    edges: &[[u32; 2]],
    triangles_at: impl Fn(u32) -> Vec<[u32; 3]>,
) -> HashMap<(u32, u32), u32> {
    let mut turns = HashMap::new();
    for &v in pinches {
        let ins: Vec<u32> = edges.iter().filter(|e| e[1] == v).map(|e| e[0]).collect();
        let outs: Vec<u32> = edges.iter().filter(|e| e[0] == v).map(|e| e[1]).collect();
        if ins.len() != 2 || outs.len() != 2 {
            continue;
        }
        let wedge = wedges(v, triangles_at(v));
        let side = |a: u32, b: u32| wedge.iter().find(|w| w.0 == [a, b]).map(|w| w.1);
        let (Some(i0), Some(i1), Some(o0), Some(o1)) = (
            side(ins[0], v),
            side(ins[1], v),
            side(v, outs[0]),
            side(v, outs[1]),
        ) else {
            continue;
        };
        // Two wedges, one edge in and one out each.
        if i0 == i1 || o0 == o1 || !((i0 == o0 && i1 == o1) || (i0 == o1 && i1 == o0)) {
            continue;
        }
        let other_out = |wedge_in: usize| if o0 == wedge_in { outs[1] } else { outs[0] };
        turns.insert((ins[0], v), other_out(i0));
        turns.insert((ins[1], v), other_out(i1));
    }
    turns
}

/// Each directed edge at `v` of the triangles around `v` (`[v, w]` or
/// `[w, v]`), with the wedge (connected fan: triangles sharing an edge at
/// `v`) its triangle belongs to.
fn wedges(v: u32, mut tris: Vec<[u32; 3]>) -> Vec<([u32; 2], usize)> {
    tris.retain(|t| t.contains(&v));
    tris.sort_unstable();
    tris.dedup();
    let mut parent: Vec<usize> = (0..tris.len()).collect();
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    let mut first_at: HashMap<u32, usize> = HashMap::new();
    for (i, t) in tris.iter().enumerate() {
        for &w in t.iter().filter(|&&w| w != v) {
            let j = *first_at.entry(w).or_insert(i);
            let (a, b) = (root(&mut parent, i), root(&mut parent, j));
            parent[a] = b;
        }
    }
    let mut out = Vec::new();
    for (i, t) in tris.iter().enumerate() {
        let r = root(&mut parent, i);
        for k in 0..3 {
            let e = [t[k], t[(k + 1) % 3]];
            if e.contains(&v) {
                out.push((e, r));
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two fans around vertex 0 that touch only there: triangles (0,1,2),
    /// (0,2,3) and (0,4,5), (0,5,6). Boundary edges at 0: 3->0, 0->1 (first
    /// wedge) and 6->0, 0->4 (second).
    #[test]
    fn the_walk_turns_into_the_other_wedge() {
        let tris = vec![[0, 1, 2], [0, 2, 3], [0, 4, 5], [0, 5, 6], [1, 2, 9]];
        let edges = [[3, 0], [0, 1], [6, 0], [0, 4]];
        let t = turns(&[0], &edges, |_| tris.clone());
        assert_eq!(t.get(&(3, 0)), Some(&4));
        assert_eq!(t.get(&(6, 0)), Some(&1));
    }

    #[test]
    fn a_vertex_whose_wedges_are_not_known_gets_no_turn() {
        // The second wedge's triangles are missing: no way to tell.
        let tris = vec![[0, 1, 2], [0, 2, 3]];
        let edges = [[3, 0], [0, 1], [6, 0], [0, 4]];
        assert!(turns(&[0], &edges, |_| tris.clone()).is_empty());
        // One wedge split in two by a missing triangle: three pieces.
        let tris = vec![[0, 1, 2], [0, 4, 5], [0, 5, 6], [0, 7, 3]];
        assert!(turns(&[0], &edges, |_| tris.clone()).is_empty());
    }
}
