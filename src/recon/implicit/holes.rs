//! Closing the holes of a closed surface: the mesh's boundary edges,
//! gathered tile by tile as the stitcher writes, chained into loops at the
//! end, and each loop of at most [`MAX_FILLED_LOOP`] vertices covered by the
//! triangulation of least area over its own vertices.
//!
//! Why: with `--closed` every lattice corner has a value, so the only holes
//! are where the zero set leaves the narrow band (the band's edge cuts it):
//! next to parts thinner than a cube, whose samples read as one sheet and
//! whose surface runs on past them. Following the surface out of the band
//! closed the 1M dragon's one hole but cost 1.6x with 72 tiles and left 14
//! on 10M (the runs go farther in cubes when cubes are smaller); a patch
//! across the band's edge is where the data stops supporting the surface
//! anyway. Deviation from paper 1, whose bounding-box lattice has no band:
//! its surface closes out there, as a bulge with nothing under it.
//!
//! The least-area triangulation of a polygon over its vertices is the
//! dynamic programme of Barequet and Sharir (1995), as used by Liepa's
//! hole filling (2003) without its refinement.
//!
//! Memory: a directed edge between two seam vertices waits in a map until
//! the neighbouring tile brings its twin, so the map is about the seam's
//! size; an edge with a vertex private to the tile is settled within it.
//! The mesh edges a patch must not repeat are kept only while one of their
//! vertices is incomplete (a later tile may name it, `super::owners`) or
//! both are on the boundary.

use super::hole_guard::{placed, tries_for, NearHoles, Placed};
use glam::DVec3;
use std::collections::{HashMap, HashSet};

/// Largest loop filled: the programme is cubic in the loop's length, and
/// a longer hole is not a leak past the band but missing data.
pub const MAX_FILLED_LOOP: usize = 400;

/// A mesh vertex: output index and position.
pub(crate) type LoopVertex = (u32, DVec3);

/// A triangle's vertices as the stitcher numbered them, with whether each
/// may be shared with another tile.
pub(crate) struct StitchedTriangle {
    pub vertices: [LoopVertex; 3],
    pub on_seam: [bool; 3],
    /// The last tile that may name each vertex.
    pub last: [u32; 3],
}

#[derive(Default)]
pub(crate) struct BoundaryEdges {
    /// Directed edges (a, b) between seam vertices whose twin (b, a) has not
    /// come yet, with their end points.
    waiting: HashMap<(u32, u32), [DVec3; 2]>,
    /// Edges without a twin, for good.
    settled: Vec<[LoopVertex; 2]>,
    /// Mesh edges (smaller index first) a patch must not repeat: those
    /// between seam vertices, and those at private vertices of a hole; with
    /// the last tile that may name each vertex.
    edges_near_holes: HashMap<(u32, u32), [u32; 2]>,
    /// The vertices of `settled`.
    settled_vertices: HashSet<u32>,
    /// Mesh triangles near the boundary, which patches must not cross.
    near: NearHoles,
}

/// What `BoundaryEdges::fill` did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct HoleReport {
    /// Boundary loops closed with a patch.
    pub filled: u64,
    /// Loops longer than [`MAX_FILLED_LOOP`], passing a vertex twice, or
    /// whose every patch would repeat a mesh edge or cross the mesh.
    pub left_open: u64,
}

impl BoundaryEdges {
    /// Counts one tile's triangles (consistently wound, so an interior edge
    /// comes once in each direction).
    pub(crate) fn add_tile(&mut self, triangles: &[StitchedTriangle]) {
        let mut local: HashMap<(u32, u32), [DVec3; 2]> = HashMap::new();
        let mut now_waiting = Vec::new();
        for t in triangles {
            for i in 0..3 {
                let j = (i + 1) % 3;
                let (a, b) = (t.vertices[i], t.vertices[j]);
                let map = if t.on_seam[i] && t.on_seam[j] {
                    &mut self.waiting
                } else {
                    &mut local
                };
                let seam = t.on_seam[i] && t.on_seam[j];
                if map.remove(&(b.0, a.0)).is_none() {
                    map.insert((a.0, b.0), [a.1, b.1]);
                    if seam {
                        now_waiting.push((a.0, b.0));
                    }
                }
            }
        }
        let at_hole: HashSet<u32> = local.keys().flat_map(|&(a, b)| [a, b]).collect();
        let mut boundary = at_hole.clone();
        boundary.extend(
            now_waiting
                .into_iter()
                .filter(|e| self.waiting.contains_key(e))
                .flat_map(|(a, b)| [a, b]),
        );
        self.near.add_tile(triangles, &boundary);
        for t in triangles {
            for i in 0..3 {
                let j = (i + 1) % 3;
                let (a, b) = (t.vertices[i].0, t.vertices[j].0);
                let between_seams = t.on_seam[i] && t.on_seam[j];
                if between_seams || at_hole.contains(&a) || at_hole.contains(&b) {
                    let (la, lb) = (t.last[i], t.last[j]);
                    let lasts = if a < b { [la, lb] } else { [lb, la] };
                    self.edges_near_holes.insert((a.min(b), a.max(b)), lasts);
                }
            }
        }
        self.settled_vertices.extend(at_hole);
        self.settled
            .extend(local.into_iter().map(|((a, b), [p, q])| [(a, p), (b, q)]));
    }

    /// Forgets the edges no patch can use once tile `tile` is stitched: a
    /// patch joins boundary vertices only, and a vertex no later tile can
    /// name is on the boundary now or never.
    pub(crate) fn retire(&mut self, tile: u32) {
        let waiting: HashSet<u32> = self.waiting.keys().flat_map(|&(a, b)| [a, b]).collect();
        let settled = &self.settled_vertices;
        let final_inside =
            |v: u32, last: u32| last <= tile && !settled.contains(&v) && !waiting.contains(&v);
        self.edges_near_holes
            .retain(|&(a, b), &mut [la, lb]| !(final_inside(a, la) || final_inside(b, lb)));
        self.near
            .retain(|v| settled.contains(&v) || waiting.contains(&v));
    }

    /// Edges kept that no patch can use (0 when every tile retired its own).
    pub(crate) fn unneeded(&self) -> u64 {
        let waiting: HashSet<u32> = self.waiting.keys().flat_map(|&(a, b)| [a, b]).collect();
        let boundary = |v: u32| self.settled_vertices.contains(&v) || waiting.contains(&v);
        let unneeded = self
            .edges_near_holes
            .keys()
            .filter(|&&(a, b)| !(boundary(a) && boundary(b)))
            .count();
        unneeded as u64
    }

    /// Chains the boundary edges into loops and triangulates each loop that
    /// can be; returns the new triangles (wound like the mesh, with their
    /// corners) and the counts.
    pub(crate) fn fill(self) -> (Vec<Placed>, HoleReport) {
        let mut edges = self.settled;
        edges.extend(
            self.waiting
                .into_iter()
                .map(|((a, b), [p, q])| [(a, p), (b, q)]),
        );
        // Hash order must not decide how a pinched loop is walked (the
        // count of loops left open changed from run to run).
        edges.sort_unstable_by_key(|[a, b]| (a.0, b.0));
        let mut report = HoleReport::default();
        let mut triangles = Vec::new();
        let is_edge = |a: u32, b: u32| self.edges_near_holes.contains_key(&(a.min(b), a.max(b)));
        let mut near = self.near;
        let turns = pinch_turns(&edges, &near);
        for (_, lp) in chain_loops(edges, &turns) {
            let patch = lp
                .filter(|l| l.len() <= MAX_FILLED_LOOP)
                .and_then(|l| patch_clear_of_mesh(&l, is_edge, &near));
            match patch {
                Some(p) => {
                    near.add_patch(&p);
                    triangles.extend_from_slice(&p);
                    report.filled += 1;
                }
                None => report.left_open += 1,
            }
        }
        (triangles, report)
    }
}

/// The loops the directed edges form, each in edge direction, in order of
/// their smallest index (so the result does not depend on hash order);
/// at a vertex with two edges out the walk takes the turn `turns` gives
/// ([`super::pinch`]); `None` for a loop that passes a vertex twice, or a
/// pinch vertex without a turn (the walk cannot tell which way to go
/// there, so it is left open). Each loop comes with the vertex its walk
/// started from.
fn chain_loops(
    edges: Vec<[LoopVertex; 2]>,
    turns: &HashMap<(u32, u32), u32>,
) -> Vec<(u32, Option<Vec<LoopVertex>>)> {
    let mut next: HashMap<u32, Vec<LoopVertex>> = HashMap::new();
    let mut starts: Vec<LoopVertex> = Vec::new();
    for [a, b] in edges {
        next.entry(a.0).or_default().push(b);
        starts.push(a);
    }
    starts.sort_by_key(|v| v.0);
    let pinches: HashSet<u32> = next
        .iter()
        .filter(|(_, out)| out.len() > 1)
        .map(|(&a, _)| a)
        .collect();
    let mut loops = Vec::new();
    for start in starts {
        let Some(first) = next.get_mut(&start.0).and_then(Vec::pop) else {
            continue;
        };
        let mut lp = vec![start];
        let mut seen = HashSet::from([start.0]);
        // A pinch vertex starting the walk: whichever edge it left by, the
        // turn into it must lead back to that edge.
        let mut ok = !pinches.contains(&start.0) || turns.values().any(|&to| to == first.0);
        let (mut prev, mut step) = (start.0, first);
        let mut closed = false;
        loop {
            if step.0 == start.0 {
                closed =
                    !pinches.contains(&start.0) || turns.get(&(prev, start.0)) == Some(&first.0);
                break;
            }
            ok &= seen.insert(step.0);
            lp.push(step);
            let Some(outs) = next.get_mut(&step.0) else {
                break;
            };
            let pick = match turns.get(&(prev, step.0)) {
                Some(&to) => outs.iter().position(|o| o.0 == to),
                None => {
                    ok &= !pinches.contains(&step.0);
                    outs.len().checked_sub(1)
                }
            };
            let Some(i) = pick else {
                break;
            };
            (prev, step) = (step.0, outs.remove(i));
        }
        loops.push((start.0, (closed && ok).then(|| start_at_least_position(lp))));
    }
    loops
}

/// The turns at the vertices with two boundary edges out.
fn pinch_turns(edges: &[[LoopVertex; 2]], near: &NearHoles) -> HashMap<(u32, u32), u32> {
    let ids: Vec<[u32; 2]> = edges.iter().map(|[a, b]| [a.0, b.0]).collect();
    let mut tails: Vec<u32> = ids.iter().map(|e| e[0]).collect();
    tails.sort_unstable();
    let pinches: Vec<u32> = tails
        .windows(2)
        .filter(|w| w[0] == w[1])
        .map(|w| w[0])
        .collect();
    let mut pinches = pinches;
    pinches.dedup();
    super::pinch::turns(&pinches, &ids, |v| near.triangles_at(v))
}

/// `lp` rotated to start at its least vertex position, so that ties in the
/// patch's areas break the same way whatever the tiling numbered.
fn start_at_least_position(mut lp: Vec<LoopVertex>) -> Vec<LoopVertex> {
    let least = (0..lp.len()).min_by(|&i, &j| {
        let (a, b) = (lp[i].1, lp[j].1);
        (a.x.total_cmp(&b.x))
            .then(a.y.total_cmp(&b.y))
            .then(a.z.total_cmp(&b.z))
    });
    if let Some(first) = least {
        lp.rotate_left(first);
    }
    lp
}

/// The least-area patch of `lp` ([`least_area_triangles`]) whose triangles
/// cross neither the mesh `near` holds nor each other: a crossing triangle
/// is banned and the programme run again, [`tries_for`] times at most.
fn patch_clear_of_mesh(
    lp: &[LoopVertex],
    is_edge: impl Fn(u32, u32) -> bool,
    near: &NearHoles,
) -> Option<Vec<Placed>> {
    let mut banned = HashSet::new();
    for _ in 0..tries_for(lp.len()) {
        let tris = least_area_triangles(lp, &is_edge, &banned)?;
        let patch: Vec<_> = tris.iter().map(|&t| placed(lp, t)).collect();
        let crossing = near.crossing(&patch);
        if crossing.is_empty() {
            return Some(patch);
        }
        for i in crossing {
            let mut key = tris[i];
            key.sort_unstable();
            banned.insert(key);
        }
    }
    None
}

/// [`least_area_triangles`] as vertex indices.
#[cfg(test)]
fn least_area_patch(
    lp: &[LoopVertex],
    is_edge: impl Fn(u32, u32) -> bool,
) -> Option<Vec<[u32; 3]>> {
    let tris = least_area_triangles(lp, is_edge, &HashSet::new())?;
    Some(tris.into_iter().map(|t| t.map(|i| lp[i].0)).collect())
}

/// The triangulation of least total area of the polygon `lp` over its own
/// vertices, wound against the polygon's direction (the mesh around a hole
/// runs along it, so the patch must run the other way), as positions in
/// `lp`. A diagonal that `is_edge` of the mesh already would make that
/// edge non-manifold, so it is never used, nor a triangle in `banned`
/// (positions ascending); `None` if no triangulation avoids them.
fn least_area_triangles(
    lp: &[LoopVertex],
    is_edge: impl Fn(u32, u32) -> bool,
    banned: &HashSet<[usize; 3]>,
) -> Option<Vec<[usize; 3]>> {
    let n = lp.len();
    if n < 3 {
        return None;
    }
    let area = |i: usize, m: usize, j: usize| {
        if banned.contains(&[i, m, j]) {
            return f64::INFINITY;
        }
        let (a, b, c) = (lp[i].1, lp[m].1, lp[j].1);
        0.5 * (b - a).cross(c - a).length()
    };
    // cost[i][j]: least area of the sub-polygon i..=j; split[i][j]: its apex.
    let mut cost = vec![0.0f64; n * n];
    let mut split = vec![0usize; n * n];
    for len in 2..n {
        for i in 0..n - len {
            let j = i + len;
            let diagonal = !(i == 0 && j == n - 1);
            if diagonal && is_edge(lp[i].0, lp[j].0) {
                cost[i * n + j] = f64::INFINITY;
                continue;
            }
            let (best, apex) = (i + 1..j)
                .map(|m| (cost[i * n + m] + cost[m * n + j] + area(i, m, j), m))
                .fold((f64::INFINITY, i + 1), |b, c| if c.0 < b.0 { c } else { b });
            cost[i * n + j] = best;
            split[i * n + j] = apex;
        }
    }
    if !cost[n - 1].is_finite() {
        return None;
    }
    // Every sub-polygon of a finite-cost triangulation has a finite cost,
    // so its apex was set.
    let mut out = Vec::with_capacity(n - 2);
    let mut stack = vec![(0, n - 1)];
    while let Some((i, j)) = stack.pop() {
        if j - i < 2 {
            continue;
        }
        let m = split[i * n + j];
        out.push([j, m, i]);
        stack.push((i, m));
        stack.push((m, j));
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{quality::quality, Mesh};

    fn v(i: u32, x: f64, y: f64, z: f64) -> LoopVertex {
        (i, DVec3::new(x, y, z))
    }

    /// An open box (five faces of a unit cube, outward winding), split over
    /// two "tiles" whose shared vertices count as seam vertices.
    fn open_box() -> Vec<[LoopVertex; 3]> {
        let p = [
            v(0, 0., 0., 0.),
            v(1, 1., 0., 0.),
            v(2, 1., 1., 0.),
            v(3, 0., 1., 0.),
            v(4, 0., 0., 1.),
            v(5, 1., 0., 1.),
            v(6, 1., 1., 1.),
            v(7, 0., 1., 1.),
        ];
        let quads = [
            [0, 3, 2, 1], // bottom, facing -z
            [0, 1, 5, 4], // front, -y
            [1, 2, 6, 5], // right, +x
            [2, 3, 7, 6], // back, +y
            [3, 0, 4, 7], // left, -x
        ];
        quads
            .iter()
            .flat_map(|q| [[p[q[0]], p[q[1]], p[q[2]]], [p[q[0]], p[q[2]], p[q[3]]]])
            .collect()
    }

    fn stitched(tris: &[[LoopVertex; 3]], seam: impl Fn(u32) -> bool) -> Vec<StitchedTriangle> {
        tris.iter()
            .map(|t| StitchedTriangle {
                vertices: *t,
                on_seam: t.map(|x| seam(x.0)),
                last: [u32::MAX; 3],
            })
            .collect()
    }

    #[test]
    fn a_hole_split_over_tiles_is_closed_with_consistent_winding() {
        let tris = open_box();
        let (first, second) = tris.split_at(5);
        // As in the stitcher: a vertex both tiles use is a seam vertex.
        let used = |part: &[[LoopVertex; 3]], i: u32| part.iter().flatten().any(|x| x.0 == i);
        let seam = |i: u32| used(first, i) && used(second, i);
        let mut edges = BoundaryEdges::default();
        edges.add_tile(&stitched(first, seam));
        edges.add_tile(&stitched(second, seam));
        let (patch, report) = edges.fill();
        assert_eq!(
            report,
            HoleReport {
                filled: 1,
                left_open: 0
            }
        );
        assert_eq!(patch.len(), 2);
        let mut vertices = vec![DVec3::ZERO; 8];
        for x in tris.iter().flatten() {
            vertices[x.0 as usize] = x.1;
        }
        let mut faces: Vec<[u32; 3]> = tris.iter().map(|t| t.map(|x| x.0)).collect();
        faces.extend(patch.iter().map(|p| p.0));
        let q = quality(&Mesh::new(vertices, faces));
        assert!(q.watertight, "{q:?}");
        assert!(q.consistently_oriented);
        assert_eq!((q.non_manifold_edges, q.euler_characteristic), (0, 2));
    }

    #[test]
    fn the_patch_has_the_least_area() {
        // A planar hexagon: every triangulation has its area (1.5 sqrt 3 for
        // unit sides), and four triangles.
        let lp: Vec<LoopVertex> = (0..6)
            .map(|k| {
                let a = std::f64::consts::PI / 3.0 * k as f64;
                v(k, a.cos(), a.sin(), 0.0)
            })
            .collect();
        let patch = least_area_patch(&lp, |_, _| false).unwrap();
        assert_eq!(patch.len(), 4);
        let area: f64 = patch
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| lp[i as usize].1);
                0.5 * (b - a).cross(c - a).length()
            })
            .sum();
        assert!((area - 1.5 * 3f64.sqrt()).abs() < 1e-12, "{area}");
        // A bent quad: the fold along the short diagonal has less area.
        let quad = [
            v(0, 0., 0., 0.),
            v(1, 1., 0., 1.),
            v(2, 2., 0., 0.),
            v(3, 1., 0.2, 0.),
        ];
        let patch = least_area_patch(&quad, |_, _| false).unwrap();
        assert!(
            patch.iter().all(|t| t.contains(&1) && t.contains(&3)),
            "{patch:?}"
        );
        // Unless that diagonal is an edge of the mesh already.
        let is_edge = |a: u32, b: u32| a.min(b) == 1 && a.max(b) == 3;
        let patch = least_area_patch(&quad, is_edge).unwrap();
        assert!(
            patch.iter().all(|t| t.contains(&0) && t.contains(&2)),
            "{patch:?}"
        );
        let no_diagonal = |a: u32, b: u32| a.abs_diff(b) == 2;
        assert_eq!(least_area_patch(&quad, no_diagonal), None);
    }

    #[test]
    fn a_pinched_loop_is_split_by_the_turns_or_left_open() {
        // Two triangles' worth of boundary meeting at vertex 0 (a bow tie).
        let e = |a: LoopVertex, b: LoopVertex| [a, b];
        let (o, a, b, c, d) = (
            v(0, 0., 0., 0.),
            v(1, 1., 0., 0.),
            v(2, 1., 1., 0.),
            v(3, -1., 0., 0.),
            v(4, -1., -1., 0.),
        );
        let edges = vec![e(o, a), e(a, b), e(b, o), e(o, c), e(c, d), e(d, o)];
        let loops = chain_loops(edges.clone(), &HashMap::new());
        assert!(loops.iter().all(|l| l.1.is_none()), "{loops:?}");
        // Turning into the other wedge (the mesh's wedges at 0 run from
        // ray 2 to ray 3 and from 4 to 1): two loops, each through 0 once.
        let turns = HashMap::from([((2, 0), 1), ((4, 0), 3)]);
        let ids = |lp: &Option<Vec<LoopVertex>>| {
            let lp = lp.as_ref().expect("a loop");
            let mut ids: Vec<u32> = lp.iter().map(|v| v.0).collect();
            ids.sort_unstable();
            ids
        };
        let loops = chain_loops(edges.clone(), &turns);
        let mut loops: Vec<Vec<u32>> = loops.iter().map(|l| ids(&l.1)).collect();
        loops.sort();
        assert_eq!(loops, vec![vec![0, 1, 2], vec![0, 3, 4]]);
        // Turning into the same wedge walks one loop through 0 twice.
        let turns = HashMap::from([((2, 0), 3), ((4, 0), 1)]);
        let loops = chain_loops(edges, &turns);
        assert!(loops.iter().all(|l| l.1.is_none()), "{loops:?}");
    }
}
