//! The surface around a small hole (a loop of boundary edges found by
//! [`super::holes`]): the triangles at and near the loop, whether they run
//! along the loop one way so a patch can be wound with them, and the
//! untwisting of a loop that does not.
//!
//! A twisted loop is paper 4's selection leaving a hole whose ring of
//! triangles turns over: steep slivers of a noisy scan, each at an obtuse
//! (compatible) angle to the next, add up to a half turn round the hole.
//! The ring is then a small Moebius band, and it is where the noisy dragon
//! was non-orientable (327k points: every non-orientable site found was a
//! dual ball of radius 4 to 8 triangles round such a hole). Deviation from
//! the paper, which stops at the deletions: the rim triangles that face
//! against the hole's plane are dropped, and the loop, grown round them, is
//! closed when it then winds one way.

use super::wind::wind;
use glam::DVec3;
use std::collections::BTreeMap;

/// An edge, as its two vertices, lower first.
pub type Edge = (u32, u32);

pub fn edge(a: u32, b: u32) -> Edge {
    (a.min(b), a.max(b))
}

/// The surface a loop sits in: the triangles at each vertex.
pub struct Rim<'a> {
    tris: &'a [[u32; 3]],
    /// Triangles at vertex `v`: `star[start[v]..start[v + 1]]`.
    start: Vec<u32>,
    star: Vec<u32>,
}

/// A loop ready to be closed: its cycle, the apex of the surface triangle
/// across each of its edges, and the rim triangles dropped to untwist it.
pub struct Ready {
    pub cycle: Vec<u32>,
    pub outer: Vec<u32>,
    pub dropped: Vec<u32>,
}

impl<'a> Rim<'a> {
    pub fn of(vertices: usize, tris: &'a [[u32; 3]]) -> Self {
        let mut start = vec![0u32; vertices + 1];
        for c in tris {
            for &v in c {
                start[v as usize + 1] += 1;
            }
        }
        for v in 0..vertices {
            start[v + 1] += start[v];
        }
        let mut fill = start.clone();
        let mut star = vec![0u32; start[vertices] as usize];
        for (t, c) in tris.iter().enumerate() {
            for &v in c {
                star[fill[v as usize] as usize] = t as u32;
                fill[v as usize] += 1;
            }
        }
        Rim { tris, start, star }
    }

    fn at(&self, v: u32) -> &[u32] {
        &self.star[self.start[v as usize] as usize..self.start[v as usize + 1] as usize]
    }

    /// The triangles (by number) with a corner on `cycle` (`rings` 1), or
    /// with a corner on one of those (`rings` 2), but those `gone` or
    /// `dropped`.
    pub fn around(&self, cycle: &[u32], rings: usize, gone: &[bool], dropped: &[u32]) -> Vec<u32> {
        let mut vertices = cycle.to_vec();
        let mut around: Vec<u32> = Vec::new();
        for _ in 0..rings {
            around = vertices
                .iter()
                .flat_map(|&v| self.at(v).iter().copied())
                .collect();
            around.retain(|&t| !gone[t as usize] && !dropped.contains(&t));
            around.sort_unstable();
            around.dedup();
            vertices = around.iter().flat_map(|&t| self.tris[t as usize]).collect();
            vertices.sort_unstable();
            vertices.dedup();
        }
        around
    }

    pub fn corners(&self, list: &[u32]) -> Vec<[u32; 3]> {
        list.iter().map(|&t| self.tris[t as usize]).collect()
    }

    /// The live triangle on edge `ab`, when it has exactly one.
    fn only_on(&self, a: u32, b: u32, gone: &[bool], dropped: &[u32]) -> Option<u32> {
        let mut on = self.at(a).iter().copied().filter(|&t| {
            !gone[t as usize] && !dropped.contains(&t) && self.tris[t as usize].contains(&b)
        });
        let first = on.next()?;
        on.next().is_none().then_some(first)
    }

    fn apex(&self, t: u32, a: u32, b: u32) -> u32 {
        let c = self.tris[t as usize];
        c.into_iter().find(|&v| v != a && v != b).unwrap_or(a)
    }

    /// `cycle` ready to be closed, untwisted if need be (see the module
    /// doc); None when it cannot be wound with the surface.
    /// The ways to ready `cycle`, least dropped first: as it is, then
    /// grown round its rim triangles that face away, round every triangle
    /// at its corners, and round those within two rings; each one that
    /// winds one way (see the module doc).
    pub fn ready(&self, points: &[DVec3], cycle: &[u32], gone: &[bool]) -> Vec<Ready> {
        let mut drops = vec![Vec::new()];
        drops.extend(self.facing_away(points, cycle, gone));
        drops.push(self.around(cycle, 1, gone, &[]));
        drops.push(self.around(cycle, 2, gone, &[]));
        drops
            .into_iter()
            .filter_map(|dropped| self.grown_ready(cycle, dropped, gone))
            .collect()
    }

    /// `cycle` grown round `dropped`, if it then winds one way.
    fn grown_ready(&self, cycle: &[u32], dropped: Vec<u32>, gone: &[bool]) -> Option<Ready> {
        let grown = self.grown(cycle, &dropped, gone)?;
        if !winds_one_way(
            &self.corners(&self.around(&grown, 1, gone, &dropped)),
            &grown,
        ) {
            return None;
        }
        let n = grown.len();
        let outer = (0..n)
            .map(|k| {
                let (a, b) = (grown[k], grown[(k + 1) % n]);
                self.only_on(a, b, gone, &dropped)
                    .map(|t| self.apex(t, a, b))
            })
            .collect::<Option<Vec<u32>>>()?;
        Some(Ready {
            cycle: grown,
            outer,
            dropped,
        })
    }

    /// The rim triangles of `cycle` that face against the hole: wound to
    /// run against the loop (as a patch's neighbour must), their normal
    /// points away from the loop's own (Newell's normal of the polygon).
    /// None when there is none to drop.
    fn facing_away(&self, points: &[DVec3], cycle: &[u32], gone: &[bool]) -> Option<Vec<u32>> {
        let p = |v: u32| points[v as usize];
        let n = cycle.len();
        let mut normal = DVec3::ZERO;
        for k in 0..n {
            normal += p(cycle[k]).cross(p(cycle[(k + 1) % n]));
        }
        let mut away = Vec::new();
        for k in 0..n {
            let (a, b) = (cycle[k], cycle[(k + 1) % n]);
            let t = self.only_on(a, b, gone, &[])?;
            let z = self.apex(t, a, b);
            if (p(a) - p(b)).cross(p(z) - p(b)).dot(normal) < 0.0 {
                away.push(t);
            }
        }
        (!away.is_empty()).then_some(away)
    }

    /// The loop round a hole grown by the `dropped` triangles: the loop's
    /// edges and theirs that keep one live triangle, as one cycle from `cycle[0]`'s side;
    /// None when they make no single simple cycle (the loop would pinch).
    fn grown(&self, cycle: &[u32], dropped: &[u32], gone: &[bool]) -> Option<Vec<u32>> {
        if dropped.is_empty() {
            return Some(cycle.to_vec());
        }
        let mut next: BTreeMap<u32, Vec<u32>> = BTreeMap::new();
        let mut edges: Vec<Edge> = self
            .corners(dropped)
            .iter()
            .flat_map(|c| [edge(c[0], c[1]), edge(c[1], c[2]), edge(c[0], c[2])])
            .chain((0..cycle.len()).map(|k| edge(cycle[k], cycle[(k + 1) % cycle.len()])))
            .collect();
        edges.sort_unstable();
        edges.dedup();
        for (a, b) in edges {
            if self.only_on(a, b, gone, dropped).is_some() {
                next.entry(a).or_default().push(b);
                next.entry(b).or_default().push(a);
            }
        }
        if next.values().any(|n| n.len() != 2) {
            return None;
        }
        let (&first, _) = next.iter().next()?;
        let mut out = vec![first];
        let mut at = (first, next[&first][0]);
        while at.1 != first {
            out.push(at.1);
            let n = &next[&at.1];
            at = (at.1, if n[0] == at.0 { n[1] } else { n[0] });
        }
        (out.len() == next.len()).then_some(out)
    }
}

/// Whether the surface `around` a loop (the triangles with a corner on it)
/// runs along `cycle` one way, so a patch can be wound with it: wound
/// consistently ([`wind`]), in each of their components the triangles on
/// the loop's edges traverse them in the same direction around the loop.
/// Otherwise the loop goes round a strip of surface with a half turn and a
/// patch would make the surface non-orientable: a hole in an orientable
/// surface is never such a loop.
pub fn winds_one_way(around: &[[u32; 3]], cycle: &[u32]) -> bool {
    let mut wound = around.to_vec();
    let report = wind(&mut wound);
    let mut way: BTreeMap<u32, bool> = BTreeMap::new();
    for k in 0..cycle.len() {
        let (a, b) = (cycle[k], cycle[(k + 1) % cycle.len()]);
        let Some(t) = wound.iter().position(|c| c.contains(&a) && c.contains(&b)) else {
            return false;
        };
        let forward = (0..3).any(|i| wound[t][i] == a && wound[t][(i + 1) % 3] == b);
        if *way.entry(report.component[t]).or_insert(forward) != forward {
            return false;
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A band of `n` quads round a loop: top `0..n`, bottom `n..2n`;
    /// `twist` joins the last quad to the first with a half turn.
    fn band(n: u32, twist: bool) -> Vec<[u32; 3]> {
        let (t, b) = (|i: u32| i % n, |i: u32| n + i % n);
        let mut tris = Vec::new();
        for i in 0..n {
            let (t1, b1) = if twist && i == n - 1 {
                (b(0), t(0))
            } else {
                (t(i + 1), b(i + 1))
            };
            tris.push([t(i), b(i), t1]);
            tris.push([b(i), b1, t1]);
        }
        tris
    }

    /// The inner loop of an untwisted band winds one way; the boundary of
    /// a Moebius band (one loop of `2n` edges) does not.
    #[test]
    fn a_twisted_loop_is_told_from_a_hole() {
        let ring = band(6, false);
        assert!(winds_one_way(&ring, &[0, 1, 2, 3, 4, 5]));
        assert!(winds_one_way(&ring, &[6, 7, 8, 9, 10, 11]));
        let moebius = band(6, true);
        let boundary = [0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11];
        assert!(!winds_one_way(&moebius, &boundary));
    }

    /// Growing a loop round a dropped rim triangle replaces its edge by
    /// the triangle's two other edges.
    #[test]
    fn a_loop_grows_round_a_dropped_triangle() {
        // The untwisted band's top loop, with the triangle on edge 0-1
        // dropped, runs 0, 6, 1 where it ran 0, 1.
        let ring = band(6, false);
        let rim = Rim::of(12, &ring);
        let gone = vec![false; ring.len()];
        let on01 = (0..ring.len() as u32)
            .find(|&t| ring[t as usize].contains(&0) && ring[t as usize].contains(&1))
            .unwrap();
        let grown = rim.grown(&[0, 1, 2, 3, 4, 5], &[on01], &gone).unwrap();
        let mut sorted = grown.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, vec![0, 1, 2, 3, 4, 5, 6]);
        let at = grown.iter().position(|&v| v == 6).unwrap();
        let (before, after) = (grown[(at + 6) % 7], grown[(at + 1) % 7]);
        assert_eq!((before.min(after), before.max(after)), (0, 1));
    }
}
