//! A tile's spanning forest contracted to its boundary, for the orientation
//! pass whose per-point state does not fit in memory ([`super::external`]).
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
//! [`contract`] computes steps 1 and 2 for one tile; [`Contraction::resolve`]
//! takes the global verdict on the tile's super-edges and the global labels
//! of its nodes and gives every core point its component label and parity.

use super::forest::Edge;
use super::unionfind::ParityUnionFind;

/// A tile's forest, contracted. Local vertex ids: core point `i` is `i`
/// (store index `start + i`), the forest's vertices outside the core follow,
/// in store order.
#[derive(Debug)]
pub struct Contraction {
    start: u32,
    count: u32,
    /// Store indices of the forest's vertices outside the core, sorted.
    foreign: Vec<u32>,
    /// The forest's edges as given, with local ends.
    edges: Vec<LocalEdge>,
    /// What happens to each edge, by position in `edges`.
    role: Vec<Role>,
    /// Local ids of the nodes, ascending.
    nodes: Vec<u32>,
    /// Which nodes are branch points (not boundary vertices), by position
    /// in `nodes`.
    branch: Vec<bool>,
    /// The super-edges, sorted by [`Edge::key`]; `slots` hold local node ids.
    supers: Vec<Edge>,
    /// Position in `edges` of each super-edge's heaviest edge.
    heaviest: Vec<u32>,
}

#[derive(Clone, Copy, Debug)]
struct LocalEdge {
    ends: [u32; 2],
    flips: bool,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Role {
    /// In the global tree whatever the other tiles hold.
    Certain,
    /// The heaviest edge of a chain: in the tree iff its super-edge is.
    Heaviest,
}

/// How [`contract`] tells the boundary: the sorted store indices of the
/// core points that other tiles' forests touch.
pub struct Boundary<'a> {
    pub core: &'a [u32],
}

/// Contracts the forest `forest` (slots are store indices) of the tile whose
/// core is store range `start..start + count`.
pub fn contract(forest: &[Edge], start: u32, count: u32, boundary: Boundary) -> Contraction {
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
    let edges: Vec<LocalEdge> = forest
        .iter()
        .map(|e| LocalEdge {
            ends: e.slots.map(local),
            flips: e.flips(),
        })
        .collect();
    let n = count as usize + foreign.len();
    let mut is_boundary = vec![false; n];
    is_boundary[count as usize..].fill(true);
    for &s in boundary.core {
        if let Some(l) = s.checked_sub(start).filter(|&l| l < count) {
            is_boundary[l as usize] = true;
        }
    }
    let graph = Adjacency::new(n, &edges);
    let mut c = Contraction {
        start,
        count,
        foreign,
        role: vec![Role::Certain; edges.len()],
        edges,
        nodes: Vec::new(),
        branch: Vec::new(),
        supers: Vec::new(),
        heaviest: Vec::new(),
    };
    let alive = graph.prune(&c.edges, &is_boundary);
    c.find_chains(forest, &graph, &alive, &is_boundary);
    c
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
    fn prune(&self, edges: &[LocalEdge], is_boundary: &[bool]) -> Vec<bool> {
        let n = is_boundary.len();
        let mut degree: Vec<u32> = (0..n as u32).map(|v| self.of(v).len() as u32).collect();
        let mut alive = vec![true; edges.len()];
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

impl Contraction {
    /// Step 2: nodes and the chains between them, as super-edges. Every
    /// boundary vertex is a node, even one whose edges were all pruned: it
    /// is where the certain edges of its tree meet the other tiles.
    fn find_chains(
        &mut self,
        forest: &[Edge],
        graph: &Adjacency,
        alive: &[bool],
        is_boundary: &[bool],
    ) {
        let n = is_boundary.len() as u32;
        let live = |v: u32| graph.of(v).iter().filter(|l| alive[l.1 as usize]).count();
        let mut is_node = vec![false; n as usize];
        for v in 0..n {
            if is_boundary[v as usize] || live(v) >= 3 {
                is_node[v as usize] = true;
                self.nodes.push(v);
                self.branch.push(!is_boundary[v as usize]);
            }
        }
        let mut walked = vec![false; self.edges.len()];
        let mut supers = Vec::new();
        for k in 0..self.nodes.len() {
            let from = self.nodes[k];
            for &(next, e) in graph.of(from) {
                if alive[e as usize] && !walked[e as usize] {
                    let chain = Chain {
                        forest,
                        graph,
                        alive,
                        is_node: &is_node,
                    };
                    supers.push(chain.walk(&self.edges, from, next, e, &mut walked));
                }
            }
        }
        supers.sort_unstable_by_key(|(s, _)| s.key());
        for &(_, h) in &supers {
            self.role[h as usize] = Role::Heaviest;
        }
        (self.supers, self.heaviest) = supers.into_iter().unzip();
    }

    /// The super-edges, sorted by [`Edge::key`]; `slots` hold local node
    /// ids (see [`Self::store_index`]).
    pub fn supers(&self) -> &[Edge] {
        &self.supers
    }

    /// Local ids of the nodes, ascending, each with whether it is a branch
    /// point (which only this tile sees) rather than a boundary vertex.
    pub fn nodes(&self) -> impl Iterator<Item = (u32, bool)> + '_ {
        self.nodes.iter().copied().zip(self.branch.iter().copied())
    }

    /// Position of node `v` (a local id) in [`Self::nodes`].
    pub fn node_position(&self, v: u32) -> usize {
        self.nodes.binary_search(&v).unwrap_or_default()
    }

    /// Store index of local vertex `v`.
    pub fn store_index(&self, v: u32) -> u32 {
        match v.checked_sub(self.count) {
            None => self.start + v,
            Some(f) => self.foreign[f as usize],
        }
    }

    /// Every core point's component label and parity (bit 63), given
    /// whether each super-edge (by position in [`Self::supers`]) is in the
    /// global tree and each node's global label and parity (`node(k)` for
    /// the `k`-th node of [`Self::nodes`]). A component no node reaches
    /// lies in this tile alone; its label is the store index of its
    /// union-find root here, a core point.
    pub fn resolve(
        &self,
        accepted: impl Fn(usize) -> bool,
        node: impl Fn(usize) -> (u64, bool),
    ) -> Vec<u64> {
        let n = self.count as usize + self.foreign.len();
        let mut in_tree: Vec<bool> = self.role.iter().map(|r| *r == Role::Certain).collect();
        for (k, &h) in self.heaviest.iter().enumerate() {
            in_tree[h as usize] = accepted(k);
        }
        let mut uf = ParityUnionFind::new(n);
        for (e, _) in self.edges.iter().zip(&in_tree).filter(|(_, t)| **t) {
            uf.union(e.ends[0], e.ends[1], e.flips);
        }
        // Each tree reached by a node takes the node's global frame.
        let mut frame: Vec<Option<(u64, bool)>> = vec![None; n];
        for (k, &v) in self.nodes.iter().enumerate() {
            let (root, p) = uf.find(v);
            if frame[root as usize].is_none() {
                let (label, parity) = node(k);
                frame[root as usize] = Some((label, parity ^ p));
            }
        }
        (0..self.count)
            .map(|i| {
                let (root, p) = uf.find(i);
                let (label, parity) = frame[root as usize]
                    .map_or((u64::from(self.start + root), p), |(l, q)| (l, p ^ q));
                label | u64::from(parity) << 63
            })
            .collect()
    }
}

/// The live forest a chain walk follows.
struct Chain<'a> {
    forest: &'a [Edge],
    graph: &'a Adjacency,
    alive: &'a [bool],
    is_node: &'a [bool],
}

impl Chain<'_> {
    /// Follows the chain leaving node `from` by edge `e` (to `next`) up to
    /// the node at its other end; returns its super-edge (local node ids as
    /// slots) and the position of its heaviest edge.
    fn walk(
        &self,
        edges: &[LocalEdge],
        from: u32,
        mut next: u32,
        mut e: u32,
        walked: &mut [bool],
    ) -> (Edge, u32) {
        let mut heaviest = e;
        let mut flips = false;
        loop {
            walked[e as usize] = true;
            flips ^= edges[e as usize].flips;
            if self.forest[e as usize].key() > self.forest[heaviest as usize].key() {
                heaviest = e;
            }
            if self.is_node[next as usize] {
                break;
            }
            // A chain vertex has exactly two live edges: take the other.
            let other = self
                .graph
                .of(next)
                .iter()
                .find(|&&(_, e2)| self.alive[e2 as usize] && e2 != e);
            let Some(&(after, e2)) = other else { break };
            (next, e) = (after, e2);
        }
        let h = self.forest[heaviest as usize];
        let w = if flips { -h.w.abs() } else { h.w.abs() };
        (
            Edge {
                w,
                a: h.a,
                b: h.b,
                slots: [from, next],
            },
            heaviest,
        )
    }
}
