//! Closing the small holes left by paper 4's selection. Deviation from
//! the paper (which stops after the deletions): samples whose neighbours
//! disagree about a nearly cocircular polygon leave holes where no fan kept
//! a triangle. Measured on 50k-point scangen shapes before this pass closed
//! loops of up to [`MAX_LOOP`] edges (it closed 3 and 4): Moebius band
//! 5 extra loops of 5 and 6 edges, sphere 5, torus 9 (5 to 8 edges), two of
//! every kind through a vertex where two holes touch (a non-manifold
//! vertex). Paper 4's boundary rule says what is a hole in the sampling: a
//! gap wider than the hole radius delta. So a cycle of boundary edges is
//! closed when it has at most [`MAX_LOOP`] edges and, with an absolute
//! delta, its corners lie within `2 delta` of each other; longer or wider
//! loops are boundaries and stay. With the local delta (5 x the corners'
//! nearest-neighbour distance, see [`super::fan::Hole::Local`]) the edge
//! count alone decides: a loop of 10 edges of about one spacing spans at
//! most 5 spacings, inside the local delta's `2 delta` of 10, while a
//! corner-based radius judges the loop by its corners' closest pairs
//! (measured on a 50k sphere: the 3-edge holes' corners had nearest
//! neighbours of a fifth of the mean spacing, that is why no fan took
//! them).
//!
//! A loop is the shortest cycle of boundary edges (order one) through a
//! boundary edge, so loops that touch at a vertex are found one by one. It
//! is triangulated by least total area (dynamic programming over the
//! polygon), never along an edge the surface already has, so every
//! boundary edge becomes an edge of two triangles and no edge gets a third.
//! Loops are taken shortest first, then by their sorted corners, and a loop
//! that shares an edge with one already closed is left: the result depends
//! on nothing but the boundary edges near the loop ([`patch_doubt`]).

use glam::DVec3;
use std::collections::{BTreeMap, BTreeSet, VecDeque};

/// Longest loop closed, in edges.
pub const MAX_LOOP: usize = 10;

type Edge = (u32, u32);

fn edge(a: u32, b: u32) -> Edge {
    (a.min(b), a.max(b))
}

/// Triangles on each edge of `tris` (corners sorted, so each edge comes
/// as `(low, high)`).
fn edge_orders(tris: &[[u32; 3]]) -> BTreeMap<Edge, u32> {
    let mut order: BTreeMap<Edge, u32> = BTreeMap::new();
    for t in tris {
        for e in [(t[0], t[1]), (t[1], t[2]), (t[0], t[2])] {
            *order.entry(e).or_default() += 1;
        }
    }
    order
}

/// Triangles that close the small holes of `tris` (corners sorted);
/// `delta` is the absolute hole radius that judges a loop (None: the local
/// one, see the module doc).
pub fn small_hole_patches(
    points: &[DVec3],
    tris: &[[u32; 3]],
    delta: Option<f64>,
) -> Vec<[u32; 3]> {
    let mut order = edge_orders(tris);
    let mut around: BTreeMap<u32, Vec<u32>> = BTreeMap::new();
    for (&(a, b), &k) in &order {
        if k == 1 {
            around.entry(a).or_default().push(b);
            around.entry(b).or_default().push(a);
        }
    }
    let known: BTreeSet<[u32; 3]> = tris.iter().copied().collect();
    let mut loops: BTreeSet<(usize, Vec<u32>)> = BTreeSet::new();
    for (&(a, b), &k) in &order {
        if k != 1 {
            continue;
        }
        if let Some(cycle) = shortest_cycle(&around, a, b) {
            if delta.is_none_or(|d| diameter(points, &cycle) <= 2.0 * d) {
                loops.insert((cycle.len(), canonical(cycle)));
            }
        }
    }
    let mut out = Vec::new();
    for (_, cycle) in loops {
        let ring: Vec<Edge> = (0..cycle.len())
            .map(|k| edge(cycle[k], cycle[(k + 1) % cycle.len()]))
            .collect();
        if ring.iter().any(|e| order.get(e) != Some(&1)) {
            continue;
        }
        let Some(patch) = least_area(points, &cycle, &order, &known) else {
            continue;
        };
        for t in &patch {
            for e in [(t[0], t[1]), (t[1], t[2]), (t[0], t[2])] {
                *order.entry(e).or_default() += 1;
            }
        }
        out.extend(patch);
    }
    out
}

/// Marks doubtful what [`small_hole_patches`] of `tris` may decide
/// differently from the whole cloud, given `doubt` closed (a triangle the
/// cloud has and this tile lacks, or the reverse, has all corners
/// doubtful): loops are found and judged over boundary edges alone, and a
/// boundary edge differs only between doubtful corners, so doubt travels
/// along boundary edges, as far as a loop search reaches and as far again
/// for the loops a closed loop blocks; then every patch with a doubtful
/// corner is doubtful in all its corners.
pub fn patch_doubt(tris: &[[u32; 3]], patches: &[[u32; 3]], doubt: &mut [bool]) {
    let boundary: Vec<Edge> = edge_orders(tris)
        .into_iter()
        .filter(|&(_, k)| k == 1)
        .map(|(e, _)| e)
        .collect();
    for _ in 0..2 * MAX_LOOP {
        let seeds = doubt.to_vec();
        for &(a, b) in &boundary {
            if seeds[a as usize] || seeds[b as usize] {
                doubt[a as usize] = true;
                doubt[b as usize] = true;
            }
        }
    }
    for t in patches {
        if t.iter().any(|&v| doubt[v as usize]) {
            for &v in t {
                doubt[v as usize] = true;
            }
        }
    }
}

/// The shortest cycle of at most [`MAX_LOOP`] boundary edges through edge
/// `ab`: a breadth-first path from `b` to `a` avoiding that edge,
/// neighbours in index order.
fn shortest_cycle(around: &BTreeMap<u32, Vec<u32>>, a: u32, b: u32) -> Option<Vec<u32>> {
    let mut parent: BTreeMap<u32, (u32, usize)> = BTreeMap::new();
    parent.insert(b, (b, 0));
    let mut queue = VecDeque::from([b]);
    while let Some(u) = queue.pop_front() {
        let depth = parent[&u].1;
        if depth + 1 >= MAX_LOOP {
            break;
        }
        for &w in around.get(&u).map(Vec::as_slice).unwrap_or(&[]) {
            if (u == b && w == a) || parent.contains_key(&w) {
                continue;
            }
            parent.insert(w, (u, depth + 1));
            if w == a {
                let mut path = vec![a];
                let mut at = a;
                while at != b {
                    at = parent[&at].0;
                    path.push(at);
                }
                return Some(path);
            }
            queue.push_back(w);
        }
    }
    None
}

/// The cycle from its smallest vertex, towards its smaller neighbour.
fn canonical(mut c: Vec<u32>) -> Vec<u32> {
    let start = (0..c.len()).min_by_key(|&k| c[k]).unwrap_or(0);
    c.rotate_left(start);
    if c.len() > 2 && c[c.len() - 1] < c[1] {
        c[1..].reverse();
    }
    c
}

fn diameter(points: &[DVec3], c: &[u32]) -> f64 {
    let mut d: f64 = 0.0;
    for (k, &u) in c.iter().enumerate() {
        for &v in &c[k + 1..] {
            d = d.max(points[u as usize].distance(points[v as usize]));
        }
    }
    d
}

fn sorted(mut t: [u32; 3]) -> [u32; 3] {
    t.sort_unstable();
    t
}

/// The least-area triangulation of polygon `c` whose diagonals are not
/// edges of the surface yet and whose triangles are not `known` (the
/// boundary of a lone triangle is a 3-cycle, not a hole); None if there is
/// none.
fn least_area(
    points: &[DVec3],
    c: &[u32],
    order: &BTreeMap<Edge, u32>,
    known: &BTreeSet<[u32; 3]>,
) -> Option<Vec<[u32; 3]>> {
    let n = c.len();
    let p = |k: usize| points[c[k] as usize];
    let free = |i: usize, j: usize| {
        j == i + 1 || (i == 0 && j == n - 1) || { !order.contains_key(&edge(c[i], c[j])) }
    };
    // cost[i][j]: the polygon i..=j closed by chord ij; split[i][j]: apex.
    let mut cost = vec![vec![f64::INFINITY; n]; n];
    let mut split = vec![vec![usize::MAX; n]; n];
    for i in 0..n - 1 {
        cost[i][i + 1] = 0.0;
    }
    for len in 2..n {
        for i in 0..n - len {
            let j = i + len;
            if !free(i, j) {
                continue;
            }
            for m in i + 1..j {
                if known.contains(&sorted([c[i], c[m], c[j]])) {
                    continue;
                }
                let area = 0.5 * (p(m) - p(i)).cross(p(j) - p(i)).length();
                let total = cost[i][m] + cost[m][j] + area;
                if total < cost[i][j] {
                    cost[i][j] = total;
                    split[i][j] = m;
                }
            }
        }
    }
    if !cost[0][n - 1].is_finite() {
        return None;
    }
    let mut out = Vec::with_capacity(n - 2);
    let mut stack = vec![(0, n - 1)];
    while let Some((i, j)) = stack.pop() {
        if j <= i + 1 {
            continue;
        }
        let m = split[i][j];
        out.push(sorted([c[i], c[m], c[j]]));
        stack.push((i, m));
        stack.push((m, j));
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Triangles of a `w` x `h` vertex grid, but for the cells `skip`.
    fn grid(w: u32, h: u32, skip: &[(u32, u32)]) -> (Vec<DVec3>, Vec<[u32; 3]>) {
        let points = (0..w * h)
            .map(|v| DVec3::new((v % w) as f64, (v / w) as f64, 0.0))
            .collect();
        let mut tris = Vec::new();
        for y in 0..h - 1 {
            for x in 0..w - 1 {
                if !skip.contains(&(x, y)) {
                    let (a, b, c, d) = (
                        y * w + x,
                        y * w + x + 1,
                        (y + 1) * w + x,
                        (y + 1) * w + x + 1,
                    );
                    tris.extend([sorted([a, b, d]), sorted([a, d, c])]);
                }
            }
        }
        (points, tris)
    }

    fn orders(tris: &[[u32; 3]]) -> BTreeMap<Edge, u32> {
        let mut order: BTreeMap<Edge, u32> = BTreeMap::new();
        for t in tris {
            for e in [(t[0], t[1]), (t[1], t[2]), (t[0], t[2])] {
                *order.entry(e).or_default() += 1;
            }
        }
        order
    }

    /// A 4x4 grid without its centre cell: the 4-edge hole is closed by two
    /// triangles and no edge gets a third; the 12-edge rim stays.
    #[test]
    fn a_quadrilateral_hole_is_closed_and_the_rim_stays() {
        let (points, mut tris) = grid(4, 4, &[(1, 1)]);
        let patches = small_hole_patches(&points, &tris, Some(10.0));
        assert_eq!(patches.len(), 2, "{patches:?}");
        tris.extend(patches);
        let order = orders(&tris);
        assert!(order.values().all(|&k| k <= 2));
        assert_eq!(order.values().filter(|&&k| k == 1).count(), 12);
    }

    /// Two triangular holes touching at one vertex (a non-manifold vertex)
    /// are both closed; a loop wider than twice the hole radius stays.
    #[test]
    fn touching_holes_are_closed_and_wide_loops_stay() {
        // A 3x3 vertex grid, triangles with the two holes at the centre 4.
        let g = |x: u32, y: u32| y * 3 + x;
        let points: Vec<DVec3> = (0..9)
            .map(|v| DVec3::new((v % 3) as f64, (v / 3) as f64, 0.0))
            .collect();
        let cells = [(0, 0), (1, 0), (0, 1), (1, 1)];
        let mut tris = Vec::new();
        for (k, &(x, y)) in cells.iter().enumerate() {
            let (a, b, c, d) = (g(x, y), g(x + 1, y), g(x, y + 1), g(x + 1, y + 1));
            // Cells 1 and 2 lose the triangle at the centre vertex 4.
            match k {
                1 => tris.push(sorted([a, b, d])),
                2 => tris.push(sorted([a, c, d])),
                _ => tris.extend([sorted([a, b, d]), sorted([a, d, c])]),
            }
        }
        let mut got = small_hole_patches(&points, &tris, Some(1.0));
        got.sort_unstable();
        assert_eq!(
            got,
            vec![
                sorted([g(1, 0), g(1, 1), g(2, 1)]),
                sorted([g(0, 1), g(1, 1), g(1, 2)])
            ]
        );
        // Too wide: the hole radius is a quarter of the holes' size.
        assert!(small_hole_patches(&points, &tris, Some(0.25)).is_empty());
    }
}
