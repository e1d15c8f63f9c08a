//! Winding the selected triangles consistently wherever the surface allows:
//! a breadth-first walk over triangles sharing an edge of order two, each
//! new triangle wound against its neighbour's direction on the shared edge.
//! A component where some edge stays traversed twice the same way cannot be
//! wound (a Moebius band): it is counted as non-orientable. Paper 4 leaves
//! the result unoriented; this is the output convention of the mesh writer.
//!
//! The walk starts each component at its triangle of smallest corners and
//! visits neighbours in sorted order, so the result depends only on the
//! triangle set (and, in [`wind_beside`], the triangles beside it).

use std::collections::VecDeque;

#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct WindReport {
    pub components: u64,
    pub non_orientable: u64,
    /// Component of each triangle (numbered from 0 in the walk's order).
    pub component: Vec<u32>,
    /// Per component: some edge could not be wound consistently.
    pub inconsistent: Vec<bool>,
}

/// Winds `tris` (rewritten in place; any corner order on entry).
pub fn wind(tris: &mut [[u32; 3]]) -> WindReport {
    wind_beside(tris, &[])
}

/// Winds `tris` as part of a larger surface that also holds `beside`: an
/// edge is crossed only when it has exactly two triangles in both lists
/// together, both in `tris`. A tile winds the triangles it owns this way,
/// with its other triangles beside them, so an edge a third triangle makes
/// non-manifold is crossed neither here nor untiled.
pub fn wind_beside(tris: &mut [[u32; 3]], beside: &[[u32; 3]]) -> WindReport {
    let mut across = neighbours(tris, beside);
    let mut seen = vec![false; tris.len()];
    let mut order: Vec<u32> = (0..tris.len() as u32).collect();
    order.sort_unstable_by_key(|&t| {
        let mut c = tris[t as usize];
        c.sort_unstable();
        c
    });
    let mut report = WindReport {
        component: vec![0; tris.len()],
        ..WindReport::default()
    };
    let mut queue = VecDeque::new();
    for &root in &order {
        if seen[root as usize] {
            continue;
        }
        let id = report.components as u32;
        report.components += 1;
        let mut consistent = true;
        seen[root as usize] = true;
        queue.push_back(root);
        while let Some(t) = queue.pop_front() {
            report.component[t as usize] = id;
            let c = tris[t as usize];
            for k in 0..3 {
                // Side `k` as `t` runs it, opposite corner `k + 2`.
                let (a, b) = (c[k], c[(k + 1) % 3]);
                let o = across[t as usize][(k + 2) % 3];
                if o == NONE {
                    continue;
                }
                let same_way = has_directed(tris[o as usize], a, b);
                if seen[o as usize] {
                    consistent &= !same_way;
                    continue;
                }
                if same_way {
                    tris[o as usize].swap(0, 1);
                    across[o as usize].swap(0, 1);
                }
                seen[o as usize] = true;
                queue.push_back(o);
            }
        }
        if !consistent {
            report.non_orientable += 1;
        }
        report.inconsistent.push(!consistent);
    }
    report
}

/// No triangle across an edge (a boundary edge, or one of more than two).
const NONE: u32 = u32::MAX;

/// Per triangle, the triangle across the edge opposite each corner, when
/// the edge has exactly two, both of `tris` (`beside` only counts): one
/// sort of all sides (a binary search per side of the walk was 2 % of the
/// Delaunay run).
fn neighbours(tris: &[[u32; 3]], beside: &[[u32; 3]]) -> Vec<[u32; 3]> {
    let mut keyed: Vec<(u64, u32)> = Vec::with_capacity((tris.len() + beside.len()) * 3);
    for (t, c) in tris.iter().chain(beside).enumerate() {
        for k in 0..3 {
            let (a, b) = (c[(k + 1) % 3], c[(k + 2) % 3]);
            keyed.push((
                (a.min(b) as u64) << 32 | a.max(b) as u64,
                t as u32 * 3 + k as u32,
            ));
        }
    }
    keyed.sort_unstable();
    let mut across = vec![[NONE; 3]; tris.len()];
    for run in keyed.chunk_by(|x, y| x.0 == y.0) {
        let ours = |side: u32| ((side / 3) as usize) < tris.len();
        if let [(_, s), (_, t)] = run {
            if !(ours(*s) && ours(*t)) {
                continue;
            }
            across[(s / 3) as usize][(s % 3) as usize] = t / 3;
            across[(t / 3) as usize][(t % 3) as usize] = s / 3;
        }
    }
    across
}

fn has_directed(c: [u32; 3], a: u32, b: u32) -> bool {
    (0..3).any(|k| c[k] == a && c[(k + 1) % 3] == b)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two triangles on an edge are wound across it, unless a third
    /// triangle beside them shares it (a non-manifold edge).
    #[test]
    fn an_edge_a_triangle_beside_shares_is_not_crossed() {
        let mut pair = [[0, 1, 2], [0, 1, 3]];
        let alone = wind(&mut pair);
        assert_eq!(alone.components, 1);
        assert_ne!(has_directed(pair[0], 0, 1), has_directed(pair[1], 0, 1));
        let mut pair = [[0, 1, 2], [0, 1, 3]];
        let beside = wind_beside(&mut pair, &[[0, 1, 4]]);
        assert_eq!(beside.components, 2);
        let elsewhere = wind_beside(&mut pair, &[[2, 3, 4]]);
        assert_eq!(elsewhere.components, 1);
    }
}
