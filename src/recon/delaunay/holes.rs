//! Closing the smallest holes left by paper 4's selection. Deviation from
//! the paper (which stops after the deletions): on noisy scans, samples
//! whose neighbours disagree about a nearly cocircular quadrilateral leave
//! holes of three or four edges where no fan kept a triangle (measured on
//! a 20k-point sphere with noise 0.05 spacings: 8 of 14 loops were
//! triangles, 3 quadrilaterals). A loop of three boundary edges gets its
//! triangle; a loop of four gets two, split along the shorter diagonal
//! unless that diagonal is already an edge. Longer loops are real
//! boundaries or holes in the sampling and stay.
//!
//! A loop is a cycle of boundary edges (order one) through vertices with
//! exactly two boundary edges each, found from its smallest vertex, so the
//! result depends on nothing but the triangle set within two rings.

use glam::DVec3;
use std::collections::{BTreeMap, BTreeSet};

/// Triangles that close the 3- and 4-edge holes of `tris` (corners sorted).
pub fn small_hole_patches(points: &[DVec3], tris: &[[u32; 3]]) -> Vec<[u32; 3]> {
    let mut order: BTreeMap<(u32, u32), u32> = BTreeMap::new();
    for t in tris {
        for e in [(t[0], t[1]), (t[1], t[2]), (t[0], t[2])] {
            *order.entry(e).or_default() += 1;
        }
    }
    let mut around: BTreeMap<u32, Vec<u32>> = BTreeMap::new();
    for (&(a, b), &k) in &order {
        if k == 1 {
            around.entry(a).or_default().push(b);
            around.entry(b).or_default().push(a);
        }
    }
    let next = |from: u32, at: u32| -> Option<u32> {
        let n = around.get(&at)?;
        (n.len() == 2).then(|| if n[0] == from { n[1] } else { n[0] })
    };
    let mut out = Vec::new();
    for (&v, n) in &around {
        if n.len() != 2 {
            continue;
        }
        // Walk from v towards its smaller neighbour; the loop is v's if v is
        // its smallest vertex and it closes within four edges.
        let mut cycle = vec![v, n[0].min(n[1])];
        while cycle.len() <= 4 {
            let (from, at) = (cycle[cycle.len() - 2], cycle[cycle.len() - 1]);
            let Some(to) = next(from, at) else { break };
            if to == v {
                break;
            }
            cycle.push(to);
        }
        let closes = next(cycle[cycle.len() - 2], cycle[cycle.len() - 1]) == Some(v);
        if !closes || cycle.iter().any(|&u| u < v) {
            continue;
        }
        match cycle.len() {
            3 => out.push(sorted([cycle[0], cycle[1], cycle[2]])),
            4 => out.extend(split_quad(points, &cycle, &order)),
            _ => {}
        }
    }
    let known: BTreeSet<[u32; 3]> = tris.iter().copied().collect();
    out.retain(|t| !known.contains(t));
    out
}

fn sorted(mut t: [u32; 3]) -> [u32; 3] {
    t.sort_unstable();
    t
}

/// Two triangles over the quadrilateral `q` (in loop order).
fn split_quad(points: &[DVec3], q: &[u32], order: &BTreeMap<(u32, u32), u32>) -> Vec<[u32; 3]> {
    let p = |v: u32| points[v as usize];
    let exists = |a: u32, b: u32| order.contains_key(&(a.min(b), a.max(b)));
    let d02 = p(q[0]).distance_squared(p(q[2]));
    let d13 = p(q[1]).distance_squared(p(q[3]));
    let first02 = d02 < d13 || (d02 == d13 && q[0].min(q[2]) < q[1].min(q[3]));
    for use02 in [first02, !first02] {
        if use02 && !exists(q[0], q[2]) {
            return vec![sorted([q[0], q[1], q[2]]), sorted([q[0], q[2], q[3]])];
        }
        if !use02 && !exists(q[1], q[3]) {
            return vec![sorted([q[1], q[2], q[3]]), sorted([q[1], q[3], q[0]])];
        }
    }
    Vec::new()
}
