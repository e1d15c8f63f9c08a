//! A tile's spanning forest contracted to its boundary, for the orientation
//! pass whose per-point state does not fit in memory ([`super::labels`]).
//!
//! The global tree of paper 1 section 2.4 is the minimum spanning forest M
//! of the union of the tile forests (see [`super::forest`]). Which edges of
//! one tile's forest F lie in M depends on the rest of the graph only
//! through F's *boundary*: the vertices some other tile's forest also
//! touches (every vertex outside the tile's core is one). So:
//!
//! 1. An edge one of whose sides (in its tree of F) holds no boundary
//!    vertex is a bridge of the whole graph: no cycle can leave that side,
//!    so it is in M whatever the other tiles hold ("certain"). Pruning
//!    non-boundary leaves one by one finds them all.
//! 2. What is left is a forest whose leaves are boundary vertices. Its
//!    nodes are the boundary vertices and the branch points (degree >= 3);
//!    between two nodes runs a chain of degree-2 vertices no other edge
//!    reaches. A cycle through one chain edge runs through the whole chain,
//!    so each chain edge but the heaviest is in M (the cut around a
//!    degree-2 vertex), and the heaviest is in M exactly when the chain,
//!    taken as one *super-edge* with the heaviest edge's key and the sum of
//!    the chain's flips, is in the minimum spanning forest of all tiles'
//!    super-edges. Both steps are the classic contraction rules of MST
//!    algorithms (cut and cycle properties), so the result is exact: the
//!    same tree, hence the same flips, as Kruskal over every point.
//!
//! [`contract`] computes steps 1 and 2 for one tile. [`resolve`] then
//! needs only the super-edges the global pass rejected: F without their
//! heaviest edges is the tile's part of M, and every tree of it that meets
//! other tiles holds a boundary vertex (a branch point's first super-edge
//! in key order is always taken, and its chains end at boundary vertices),
//! whose global label and parity it takes.

use super::forest::Edge;
use super::unionfind::ParityUnionFind;

/// A tile's forest with local vertex ids: core point `i` is `i` (store
/// index `start + i`); the forest's vertices outside the core follow, in
/// store order.
#[derive(Debug)]
pub struct LocalForest {
    start: u32,
    count: u32,
    /// Store indices of the forest's vertices outside the core, sorted.
    foreign: Vec<u32>,
    edges: Vec<LocalEdge>,
}

#[derive(Clone, Copy, Debug)]
struct LocalEdge {
    ends: [u32; 2],
    flips: bool,
}

impl LocalForest {
    /// The forest `forest` (slots are store indices) of the tile whose core
    /// is store range `start..start + count`.
    pub fn new(forest: &[Edge], start: u32, count: u32) -> Self {
        let mut foreign: Vec<u32> = forest
            .iter()
            .flat_map(|e| e.slots)
            .filter(|&s| s.wrapping_sub(start) >= count)
            .collect();
        foreign.sort_unstable();
        foreign.dedup();
        let local = |s: u32| match s.wrapping_sub(start) {
            l if l < count => l,
            _ => count + foreign.binary_search(&s).unwrap_or_default() as u32,
        };
        let edges = forest
            .iter()
            .map(|e| LocalEdge {
                ends: e.slots.map(local),
                flips: e.flips(),
            })
            .collect();
        LocalForest {
            start,
            count,
            foreign,
            edges,
        }
    }

    fn vertices(&self) -> usize {
        self.count as usize + self.foreign.len()
    }

    /// Store index of local vertex `v`.
    pub fn store_index(&self, v: u32) -> u32 {
        match v.checked_sub(self.count) {
            None => self.start + v,
            Some(f) => self.foreign[f as usize],
        }
    }

    /// Which local vertices are boundary vertices: every one outside the
    /// core, and the core points in `core` (sorted store indices).
    fn boundary(&self, core: &[u32]) -> Vec<bool> {
        let mut is_boundary = vec![false; self.vertices()];
        is_boundary[self.count as usize..].fill(true);
        for &s in core {
            if let Some(l) = s.checked_sub(self.start).filter(|&l| l < self.count) {
                is_boundary[l as usize] = true;
            }
        }
        is_boundary
    }
}

/// A tile forest's nodes and super-edges.
#[derive(Debug)]
pub struct Contraction {
    /// Local ids of the nodes, ascending.
    nodes: Vec<u32>,
    /// Which nodes are branch points (not boundary vertices), by position
    /// in `nodes`.
    branch: Vec<bool>,
    /// Store index of each node, by position in `nodes`.
    stores: Vec<u32>,
    /// The super-edges, sorted by [`Edge::key`]; `slots` hold local node
    /// ids, `a`, `b` and `|w|` are the heaviest chain edge's.
    supers: Vec<Edge>,
}

impl Contraction {
    /// The super-edges, sorted by [`Edge::key`] (see the field).
    pub fn supers(&self) -> &[Edge] {
        &self.supers
    }

    /// The nodes in ascending local id: each one's store index and whether
    /// it is a branch point (which only this tile sees) rather than a
    /// boundary vertex.
    pub fn nodes(&self) -> impl Iterator<Item = (u32, bool)> + '_ {
        self.stores.iter().copied().zip(self.branch.iter().copied())
    }

    /// Position of node `v` (a local id) in [`Self::nodes`].
    pub fn node_position(&self, v: u32) -> usize {
        self.nodes.binary_search(&v).unwrap_or_default()
    }
}

/// Contracts `local`, the forest `forest`, given the core points other
/// tiles' forests touch (`boundary_core`, sorted store indices).
pub fn contract(forest: &[Edge], local: &LocalForest, boundary_core: &[u32]) -> Contraction {
    let is_boundary = local.boundary(boundary_core);
    let graph = Adjacency::new(local.vertices(), &local.edges);
    let alive = graph.prune(&is_boundary);
    let mut c = Contraction {
        nodes: Vec::new(),
        branch: Vec::new(),
        stores: Vec::new(),
        supers: Vec::new(),
    };
    let live = |v: u32| graph.of(v).iter().filter(|l| alive[l.1 as usize]).count();
    // Every boundary vertex is a node, even one whose edges were all
    // pruned: it is where the certain edges of its tree meet other tiles.
    let mut is_node = vec![false; is_boundary.len()];
    for v in 0..is_boundary.len() as u32 {
        if is_boundary[v as usize] || live(v) >= 3 {
            is_node[v as usize] = true;
            c.nodes.push(v);
            c.branch.push(!is_boundary[v as usize]);
            c.stores.push(local.store_index(v));
        }
    }
    let chain = Chain {
        forest,
        edges: &local.edges,
        graph: &graph,
        alive: &alive,
        is_node: &is_node,
    };
    let mut walked = vec![false; forest.len()];
    for &from in &c.nodes {
        for &(next, e) in graph.of(from) {
            if alive[e as usize] && !walked[e as usize] {
                c.supers.push(chain.walk(from, next, e, &mut walked));
            }
        }
    }
    c.supers.sort_unstable_by_key(Edge::key);
    c
}

/// Every core point's component label and parity (bit 63): the tile's part
/// of the global tree is its forest without the heaviest edges of the
/// rejected super-edges (`rejected`: their `(a, b)` ids, sorted); a tree of
/// it holding a boundary vertex takes that vertex's global label and parity
/// (`frame(store index)`); any other lies in this tile alone and is
/// labelled by the store index of its union-find root here, a core point.
pub fn resolve(
    forest: &[Edge],
    local: &LocalForest,
    rejected: &[(u32, u32)],
    boundary_core: &[u32],
    frame: impl Fn(u32) -> (u64, bool),
) -> Vec<u64> {
    let n = local.vertices();
    let mut uf = ParityUnionFind::new(n);
    for (e, l) in forest.iter().zip(&local.edges) {
        if rejected.binary_search(&(e.a, e.b)).is_err() {
            uf.union(l.ends[0], l.ends[1], l.flips);
        }
    }
    let is_boundary = local.boundary(boundary_core);
    let mut root_frame: Vec<Option<(u64, bool)>> = vec![None; n];
    for v in (0..n as u32).filter(|&v| is_boundary[v as usize]) {
        let (root, p) = uf.find(v);
        if root_frame[root as usize].is_none() {
            let (label, parity) = frame(local.store_index(v));
            root_frame[root as usize] = Some((label, parity ^ p));
        }
    }
    (0..local.count)
        .map(|i| {
            let (root, p) = uf.find(i);
            let (label, parity) = root_frame[root as usize]
                .map_or((u64::from(local.start + root), p), |(l, q)| (l, p ^ q));
            label | u64::from(parity) << 63
        })
        .collect()
}

/// Forest adjacency in compressed rows: `(neighbour, edge)` per incidence.
struct Adjacency {
    first: Vec<u32>,
    links: Vec<(u32, u32)>,
}

impl Adjacency {
    fn new(n: usize, edges: &[LocalEdge]) -> Self {
        let mut first = vec![0u32; n + 1];
        for e in edges {
            for v in e.ends {
                first[v as usize + 1] += 1;
            }
        }
        for v in 0..n {
            first[v + 1] += first[v];
        }
        let mut fill = first.clone();
        let mut links = vec![(0, 0); 2 * edges.len()];
        for (i, e) in edges.iter().enumerate() {
            let [a, b] = e.ends;
            links[fill[a as usize] as usize] = (b, i as u32);
            fill[a as usize] += 1;
            links[fill[b as usize] as usize] = (a, i as u32);
            fill[b as usize] += 1;
        }
        Adjacency { first, links }
    }

    fn of(&self, v: u32) -> &[(u32, u32)] {
        &self.links[self.first[v as usize] as usize..self.first[v as usize + 1] as usize]
    }

    /// Step 1: strips non-boundary leaves until none is left; returns which
    /// edges survive (the pruned ones are certain).
    fn prune(&self, is_boundary: &[bool]) -> Vec<bool> {
        let n = is_boundary.len();
        let mut degree: Vec<u32> = (0..n as u32).map(|v| self.of(v).len() as u32).collect();
        let mut alive = vec![true; self.links.len() / 2];
        let mut leaves: Vec<u32> = (0..n as u32)
            .filter(|&v| degree[v as usize] == 1 && !is_boundary[v as usize])
            .collect();
        while let Some(v) = leaves.pop() {
            let Some(&(u, e)) = self.of(v).iter().find(|&&(_, e)| alive[e as usize]) else {
                continue;
            };
            alive[e as usize] = false;
            degree[v as usize] = 0;
            degree[u as usize] -= 1;
            if degree[u as usize] == 1 && !is_boundary[u as usize] {
                leaves.push(u);
            }
        }
        alive
    }
}

/// The live forest a chain walk follows.
struct Chain<'a> {
    forest: &'a [Edge],
    edges: &'a [LocalEdge],
    graph: &'a Adjacency,
    alive: &'a [bool],
    is_node: &'a [bool],
}

impl Chain<'_> {
    /// Follows the chain leaving node `from` by edge `e` (to `next`) up to
    /// the node at its other end; returns its super-edge (local node ids as
    /// slots, the heaviest edge's ids and cost, the chain's flips).
    fn walk(&self, from: u32, mut next: u32, mut e: u32, walked: &mut [bool]) -> Edge {
        let mut heaviest = e;
        let mut flips = false;
        loop {
            walked[e as usize] = true;
            flips ^= self.edges[e as usize].flips;
            if self.forest[e as usize].key() > self.forest[heaviest as usize].key() {
                heaviest = e;
            }
            if self.is_node[next as usize] {
                break;
            }
            // A chain vertex has exactly two live edges: take the other.
            let live = |&&(_, e2): &&(u32, u32)| self.alive[e2 as usize] && e2 != e;
            let Some(&(after, e2)) = self.graph.of(next).iter().find(live) else {
                break;
            };
            (next, e) = (after, e2);
        }
        let h = self.forest[heaviest as usize];
        Edge {
            w: if flips { -h.w.abs() } else { h.w.abs() },
            a: h.a,
            b: h.b,
            slots: [from, next],
        }
    }
}
