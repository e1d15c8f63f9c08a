//! The feature-line graph (vertices, edges with a kind, corner marks), its
//! relaxation (paper 5 section 5, Fig. 10), its measures, and reading its
//! PLY file back (writing it, in every format, is `super::line_files`').

use crate::geom::LineKind;
use crate::io::IoError;
use glam::DVec3;
use std::collections::{HashMap, HashSet};
use std::path::Path;

/// Rounds of [`LineGraph::prune`] at most (a spur rarely hides more than
/// one behind it).
const MAX_PRUNE_ROUNDS: usize = 4;

/// Polylines as a graph.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LineGraph {
    /// Polyline vertex positions.
    pub vertices: Vec<DVec3>,
    /// Segments `(a, b, kind)` between vertices `a` and `b`.
    pub edges: Vec<(u32, u32, LineKind)>,
    /// Per vertex: a corner (lines meet there).
    pub corners: Vec<bool>,
}

impl LineGraph {
    fn degrees(&self) -> Vec<u32> {
        let mut deg = vec![0u32; self.vertices.len()];
        for &(a, b, _) in &self.edges {
            deg[a as usize] += 1;
            deg[b as usize] += 1;
        }
        deg
    }

    /// Removes vertices no edge uses (renumbering the rest in order).
    pub(crate) fn drop_isolated(&mut self) {
        let deg = self.degrees();
        let mut map = vec![u32::MAX; self.vertices.len()];
        let mut next = 0u32;
        let mut vertices = Vec::new();
        let mut corners = Vec::new();
        for (i, d) in deg.iter().enumerate() {
            if *d > 0 {
                map[i] = next;
                next += 1;
                vertices.push(self.vertices[i]);
                corners.push(self.corners.get(i).copied().unwrap_or(false));
            }
        }
        for e in &mut self.edges {
            e.0 = map[e.0 as usize];
            e.1 = map[e.1 as usize];
        }
        self.vertices = vertices;
        self.corners = corners;
    }

    /// The chains between fixed vertices (degree other than 2, or
    /// corners), and cycles, as vertex sequences.
    pub(crate) fn chains(&self) -> Vec<Vec<u32>> {
        let n = self.vertices.len();
        let adj = Adjacency::new(n, &self.edges);
        let fixed =
            |v: usize| adj.at(v).len() != 2 || self.corners.get(v).copied().unwrap_or(false);
        let mut used = vec![false; self.edges.len()];
        let mut chains = Vec::new();
        let walk = |start: usize, first: (u32, u32), used: &mut Vec<bool>| {
            let mut chain = vec![start as u32];
            let (mut v, mut e) = first;
            loop {
                used[e as usize] = true;
                chain.push(v);
                if fixed(v as usize) || v as usize == start {
                    return chain;
                }
                match adj.at(v as usize).iter().find(|(_, f)| !used[*f as usize]) {
                    Some(&next) => (v, e) = next,
                    None => return chain,
                }
            }
        };
        for s in (0..n).filter(|&v| fixed(v)) {
            for &first in adj.at(s) {
                if !used[first.1 as usize] {
                    chains.push(walk(s, first, &mut used));
                }
            }
        }
        // What is left are cycles of degree-2 vertices.
        for s in 0..n {
            if let Some(&first) = adj.at(s).iter().find(|(_, e)| !used[*e as usize]) {
                chains.push(walk(s, first, &mut used));
            }
        }
        chains
    }

    /// Drops the short ends of the graph: a chain shorter than `shortest`
    /// with a free end (degree 1) whose other end is free too (a short line
    /// on its own) or a junction (a spur off another line); and of two
    /// chains between the same two junctions (a line grown twice, side by
    /// side, and joined at both ends), the longer. Repeated while one goes
    /// (a removal may leave another). A junction left with two edges is no
    /// corner any more. Deviation from paper 5, named:
    /// the paper keeps every grown line; Ohtake et al. 2004 drop lines whose
    /// strength (the curvature integrated along them) is small. A line
    /// shorter than the repair's cone is one the growth could not carry
    /// over a few spacings: noise beside a line, or a crest too short to
    /// be told from noise.
    pub(crate) fn prune(&mut self, shortest: f64) {
        for _ in 0..MAX_PRUNE_ROUNDS {
            let deg = self.degrees();
            let mut cut = Vec::new();
            let mut twins: HashMap<(u32, u32), (f64, usize)> = HashMap::new();
            let chains = self.chains();
            for (i, c) in chains.iter().enumerate() {
                let (Some(&a), Some(&b)) = (c.first(), c.last()) else {
                    continue;
                };
                let (da, db) = (deg[a as usize], deg[b as usize]);
                let length = self.chain_length(c);
                let spur = (da == 1 && (db == 1 || db >= 3)) || (db == 1 && da >= 3);
                if a != b && spur && length < shortest {
                    cut.push(i);
                } else if a != b && da >= 3 && db >= 3 {
                    // Two chains between the same junctions: one line grown
                    // twice side by side; the shorter (straighter) stays.
                    let key = (a.min(b), a.max(b));
                    match twins.get_mut(&key) {
                        Some(kept) if kept.0 <= length => cut.push(i),
                        Some(kept) => {
                            cut.push(kept.1);
                            *kept = (length, i);
                        }
                        None => {
                            twins.insert(key, (length, i));
                        }
                    }
                }
            }
            if cut.is_empty() {
                break;
            }
            self.cut_chains(cut.iter().map(|&i| chains[i].as_slice()));
        }
        self.drop_isolated();
    }

    fn chain_length(&self, c: &[u32]) -> f64 {
        c.windows(2)
            .map(|w| self.vertices[w[0] as usize].distance(self.vertices[w[1] as usize]))
            .sum()
    }

    /// Removes the edges of `chains`; a junction left with two edges is
    /// no corner any more.
    fn cut_chains<'c>(&mut self, chains: impl Iterator<Item = &'c [u32]> + Clone) {
        let before = self.degrees();
        let cut: HashSet<(u32, u32)> = chains
            .clone()
            .flat_map(|c| c.windows(2).map(|w| (w[0].min(w[1]), w[0].max(w[1]))))
            .collect();
        self.edges
            .retain(|&(a, b, _)| !cut.contains(&(a.min(b), a.max(b))));
        let after = self.degrees();
        for c in chains {
            for v in [c.first(), c.last()].into_iter().flatten() {
                let v = *v as usize;
                if before[v] >= 3 && after[v] == 2 {
                    if let Some(mark) = self.corners.get_mut(v) {
                        *mark = false;
                    }
                }
            }
        }
    }

    /// `passes` relaxation passes (Fig. 10): along each chain, each
    /// interior vertex in turn moves onto the perpendicular bisector of its
    /// two neighbours (the earlier one already moved) in their plane,
    /// keeping the triangle's area; chain ends stay.
    pub(crate) fn relax(&mut self, passes: usize) {
        let chains = self.chains();
        for _ in 0..passes {
            for c in &chains {
                for w in 0..c.len().saturating_sub(2) {
                    let (a, b, m) = (c[w] as usize, c[w + 2] as usize, c[w + 1] as usize);
                    self.vertices[m] =
                        bisected(self.vertices[a], self.vertices[m], self.vertices[b]);
                }
            }
        }
    }

    /// Total length of the edges.
    pub(crate) fn length(&self) -> f64 {
        // A fold from +0: `sum` of no f64 is -0, printed "-0.0000e0".
        self.edges
            .iter()
            .map(|&(a, b, _)| self.vertices[a as usize].distance(self.vertices[b as usize]))
            .fold(0.0, |s, l| s + l)
    }

    /// Connected components with at least one edge (the polylines).
    pub(crate) fn components(&self) -> usize {
        let mut uf: Vec<u32> = (0..self.vertices.len() as u32).collect();
        fn find(uf: &mut [u32], mut v: u32) -> u32 {
            while uf[v as usize] != v {
                uf[v as usize] = uf[uf[v as usize] as usize];
                v = uf[v as usize];
            }
            v
        }
        let mut count = self.vertices.len();
        for &(a, b, _) in &self.edges {
            let (ra, rb) = (find(&mut uf, a), find(&mut uf, b));
            if ra != rb {
                uf[ra as usize] = rb;
                count -= 1;
            }
        }
        count - self.degrees().iter().filter(|d| **d == 0).count()
    }

    pub(crate) fn corner_count(&self) -> usize {
        self.corners.iter().filter(|c| **c).count()
    }
}

impl LineGraph {
    /// Reads a line file as [`LineGraph::write`] writes it (PLY binary
    /// little-endian or ASCII with `x y z` double and `vertex1 vertex2`
    /// int, `kind` uchar); anything else is an error naming the file.
    pub fn read(path: &Path) -> Result<LineGraph, IoError> {
        let bytes = std::fs::read(path).map_err(|e| IoError::os(path, e))?;
        let bad = |reason: &str| IoError::Unsupported {
            path: path.to_path_buf(),
            reason: format!("not a scanmesh feature-line PLY: {reason}"),
        };
        let end = bytes
            .windows(11)
            .position(|w| w == b"end_header\n")
            .ok_or_else(|| bad("no end_header"))?;
        let header = std::str::from_utf8(&bytes[..end]).map_err(|_| bad("header not text"))?;
        let count = |name: &str| -> Result<usize, IoError> {
            header
                .lines()
                .find_map(|l| l.strip_prefix(&format!("element {name} ")))
                .and_then(|n| n.trim().parse().ok())
                .ok_or_else(|| bad(&format!("no element {name}")))
        };
        let (nv, ne) = (count("vertex")?, count("edge")?);
        let ascii = header.contains("format ascii");
        if !ascii && !header.contains("format binary_little_endian") {
            return Err(bad("format must be ascii or binary_little_endian"));
        }
        let body = &bytes[end + 11..];
        let mut g = LineGraph {
            corners: vec![false; nv],
            ..LineGraph::default()
        };
        let kind_of = |k: u8| match k {
            1 => Ok(LineKind::Ridge),
            2 => Ok(LineKind::Valley),
            _ => Err(bad(&format!("edge kind {k}"))),
        };
        if ascii {
            let text = std::str::from_utf8(body).map_err(|_| bad("body not text"))?;
            let mut lines = text.lines();
            for _ in 0..nv {
                let v: Vec<f64> = lines
                    .next()
                    .ok_or_else(|| bad("short vertex list"))?
                    .split_whitespace()
                    .map(|t| t.parse().map_err(|_| bad("bad number")))
                    .collect::<Result<_, _>>()?;
                match v.as_slice() {
                    [x, y, z] => g.vertices.push(DVec3::new(*x, *y, *z)),
                    _ => return Err(bad("a vertex needs x y z")),
                }
            }
            for _ in 0..ne {
                let v: Vec<i64> = lines
                    .next()
                    .ok_or_else(|| bad("short edge list"))?
                    .split_whitespace()
                    .map(|t| t.parse().map_err(|_| bad("bad integer")))
                    .collect::<Result<_, _>>()?;
                match v.as_slice() {
                    [a, b, k] => g.edges.push((*a as u32, *b as u32, kind_of(*k as u8)?)),
                    _ => return Err(bad("an edge needs vertex1 vertex2 kind")),
                }
            }
        } else {
            if body.len() < nv * 24 + ne * 9 {
                return Err(bad("file shorter than its header says"));
            }
            let f = |o: usize| f64::from_le_bytes(body[o..o + 8].try_into().unwrap_or([0; 8]));
            for i in 0..nv {
                g.vertices
                    .push(DVec3::new(f(24 * i), f(24 * i + 8), f(24 * i + 16)));
            }
            let e0 = nv * 24;
            for i in 0..ne {
                let r = &body[e0 + 9 * i..e0 + 9 * i + 9];
                let a = i32::from_le_bytes([r[0], r[1], r[2], r[3]]);
                let b = i32::from_le_bytes([r[4], r[5], r[6], r[7]]);
                g.edges.push((a as u32, b as u32, kind_of(r[8])?));
            }
        }
        if g.edges
            .iter()
            .any(|e| e.0 as usize >= nv || e.1 as usize >= nv)
        {
            return Err(bad("an edge names a vertex beyond the list"));
        }
        Ok(g)
    }

    /// A graph of true segments (each its own two vertices).
    pub fn from_segments(segs: &[crate::synth::TrueSegment]) -> LineGraph {
        let mut g = LineGraph::default();
        for s in segs {
            let v = g.vertices.len() as u32;
            g.vertices.extend([s.a, s.b]);
            g.edges.push((v, v + 1, s.kind));
        }
        g.corners = vec![false; g.vertices.len()];
        g
    }
}

/// `m` moved onto the perpendicular bisector of `a b` in the plane of the
/// three, at the same distance from the line `a b` (same triangle area).
/// Each vertex's `(neighbour, edge)` pairs in edge order, in one array
/// (a `Vec` per vertex cost ~70 bytes a vertex, at the join's peak).
struct Adjacency {
    start: Vec<u32>,
    pairs: Vec<(u32, u32)>,
}

impl Adjacency {
    fn new(n: usize, edges: &[(u32, u32, LineKind)]) -> Self {
        let mut start = vec![0u32; n + 1];
        for &(a, b, _) in edges {
            start[a as usize + 1] += 1;
            start[b as usize + 1] += 1;
        }
        for v in 0..n {
            start[v + 1] += start[v];
        }
        let mut next = start.clone();
        let mut pairs = vec![(0, 0); start[n] as usize];
        for (e, &(a, b, _)) in edges.iter().enumerate() {
            for (v, w) in [(a, b), (b, a)] {
                pairs[next[v as usize] as usize] = (w, e as u32);
                next[v as usize] += 1;
            }
        }
        Adjacency { start, pairs }
    }

    fn at(&self, v: usize) -> &[(u32, u32)] {
        &self.pairs[self.start[v] as usize..self.start[v + 1] as usize]
    }
}

fn bisected(a: DVec3, m: DVec3, b: DVec3) -> DVec3 {
    let ab = b - a;
    let len2 = ab.length_squared();
    if len2 == 0.0 {
        return m;
    }
    let mid = (a + b) * 0.5;
    let off = (m - a) - ab * ((m - a).dot(ab) / len2);
    mid + off
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A graph of the polylines `lines` (vertex positions on the x-y plane).
    fn graph(lines: &[&[(f64, f64)]]) -> LineGraph {
        let mut g = LineGraph::default();
        let mut at = std::collections::HashMap::new();
        for line in lines {
            let ids: Vec<u32> = line
                .iter()
                .map(|&(x, y)| {
                    *at.entry((x.to_bits(), y.to_bits())).or_insert_with(|| {
                        g.vertices.push(DVec3::new(x, y, 0.0));
                        g.vertices.len() as u32 - 1
                    })
                })
                .collect();
            for w in ids.windows(2) {
                g.edges.push((w[0], w[1], LineKind::Ridge));
            }
        }
        g.corners = vec![false; g.vertices.len()];
        g
    }

    /// A spur shorter than the limit goes, a long branch stays, and the
    /// junction the spur left is no corner.
    #[test]
    fn prune_drops_short_spurs_and_short_lines_only() {
        let main: &[(f64, f64)] = &[(0.0, 0.0), (1.0, 0.0), (2.0, 0.0), (3.0, 0.0)];
        let spur: &[(f64, f64)] = &[(1.0, 0.0), (1.0, 0.5)];
        let branch: &[(f64, f64)] = &[(2.0, 0.0), (2.0, 1.0), (2.0, 2.0)];
        let alone: &[(f64, f64)] = &[(5.0, 5.0), (5.5, 5.0)];
        let mut g = graph(&[main, spur, branch, alone]);
        g.corners[1] = true;
        g.prune(1.0);
        assert_eq!(g.edges.len(), 5, "{:?}", g.edges);
        assert_eq!(g.vertices.len(), 6);
        assert!((g.length() - 5.0).abs() < 1e-12);
        let at = |x: f64, y: f64| g.vertices.iter().position(|v| *v == DVec3::new(x, y, 0.0));
        assert_eq!(at(1.0, 0.5), None);
        assert_eq!(at(5.0, 5.0), None);
        let junction = at(1.0, 0.0).expect("kept");
        assert!(!g.corners[junction], "a vertex of degree 2 is no corner");
    }

    /// Two chains between the same two junctions: the longer goes.
    #[test]
    fn prune_keeps_the_shorter_of_twin_chains() {
        let left: &[(f64, f64)] = &[(-1.0, 0.0), (0.0, 0.0)];
        let straight: &[(f64, f64)] = &[(0.0, 0.0), (1.0, 0.0), (2.0, 0.0)];
        let bowed: &[(f64, f64)] = &[(0.0, 0.0), (1.0, 0.4), (2.0, 0.0)];
        let right: &[(f64, f64)] = &[(2.0, 0.0), (3.0, 0.0)];
        let mut g = graph(&[left, straight, bowed, right]);
        g.prune(0.5);
        assert_eq!(g.edges.len(), 4);
        assert!((g.length() - 4.0).abs() < 1e-12, "{}", g.length());
    }

    #[test]
    fn relaxation_centres_vertices_and_keeps_area() {
        let a = DVec3::ZERO;
        let b = DVec3::new(2.0, 0.0, 0.0);
        let m = DVec3::new(0.3, 0.5, 0.0);
        let r = bisected(a, m, b);
        assert!((r - DVec3::new(1.0, 0.5, 0.0)).length() < 1e-12, "{r}");
    }

    #[test]
    fn chains_split_at_corners_and_ends() {
        // A T: 0-1-2 with 3 hanging off 1, plus a separate triangle loop.
        let mut g = LineGraph {
            vertices: vec![DVec3::ZERO; 7],
            edges: vec![
                (0, 1, LineKind::Ridge),
                (1, 2, LineKind::Ridge),
                (1, 3, LineKind::Ridge),
                (4, 5, LineKind::Valley),
                (5, 6, LineKind::Valley),
                (6, 4, LineKind::Valley),
            ],
            corners: vec![false; 7],
        };
        assert_eq!(g.chains().len(), 4);
        assert_eq!(g.components(), 2);
        g.corners[5] = true;
        let c = g.chains();
        assert!(
            c.iter().any(|c| c.len() == 4 && c[0] == 5 && c[3] == 5),
            "{c:?}"
        );
    }
}
