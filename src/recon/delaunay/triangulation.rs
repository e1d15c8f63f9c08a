//! The 3-D Delaunay triangulation itself: a compact array of tetrahedra
//! (vertices and neighbours, 32 bytes a cell, no allocation per cell) built
//! by incremental Bowyer-Watson insertion.
//!
//! Paper 4 section 2.1 inserts into an auxiliary tetrahedron whose vertices
//! lie 3r from the centre. Deviation: the hull is closed with one vertex at
//! infinity instead (as CGAL does), so the result is the exact Delaunay
//! triangulation of the points. Tiles rely on that: a triangle a tile
//! proves Delaunay must be a triangle of the whole cloud's triangulation,
//! and auxiliary vertices would change which triangles exist near a tile's
//! edge (and differ between tiles).
//!
//! Insertion of `p`: locate a cell in conflict by a visibility walk from the
//! last new cell (the insertion order is spatially coherent, see
//! [`super::order`]); grow the conflict region (cells whose circumsphere
//! holds `p`, or, for a cell on the hull, whose outer half-space does) by a
//! depth-first search; replace it by the cone from `p` over its boundary.
//! Freed cells are reused. The new cells' faces through `p` are paired by
//! their edge in a small open-addressing table, cleared by generation.

use super::order::{insertion_order, InsertionOrder};
use super::predicates::{collinear, in_circle_perturbed, in_sphere_perturbed, orient};
use glam::DVec3;

/// The vertex at infinity.
pub const INFINITE: u32 = 0x7FFF_FFFF;
/// `v[0]` of a free cell slot.
const FREE: u32 = 0x7FFF_FFFE;
/// During one insertion, the top bit of `v[0]` marks a cell in conflict and
/// that of `v[1]` a cell tested and not in conflict (vertex numbers use 31
/// bits): the mark shares the cell's cache line, where a separate mark
/// array cost a second cache miss per test. Both are clear between
/// insertions.
const IN: u32 = 1 << 31;
const OUT: u32 = 1 << 31;
/// `EDGE_OF[j][k]`: the two slots of a cell other than `j` and `k`.
const EDGE_OF: [[[usize; 2]; 4]; 4] = {
    let mut t = [[[0; 2]; 4]; 4];
    let mut j = 0;
    while j < 4 {
        let mut k = 0;
        while k < 4 {
            let (mut m, mut i) = (0, 0);
            while i < 4 {
                if i != j && i != k && m < 2 {
                    t[j][k][m] = i;
                    m += 1;
                }
                i += 1;
            }
            k += 1;
        }
        j += 1;
    }
    t
};
/// Cells are addressed with 30 bits (the neighbour field keeps 2 for the face).
const MAX_CELLS: usize = 1 << 30;

/// One tetrahedron: `v[j]` its vertices (one may be [`INFINITE`]), `n[j]`
/// the neighbour across the face opposite `v[j]`, as `cell << 2 | face`
/// where `face` is this face's index in the neighbour.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Cell {
    /// Vertices, as indices into the triangulated points, or [`INFINITE`].
    pub v: [u32; 4],
    /// Neighbour across the face opposite each vertex, as `cell << 2 | face`.
    pub n: [u32; 4],
}

impl Cell {
    /// Whether the slot is on the free list (no live cell).
    pub fn is_free(&self) -> bool {
        self.v[0] == FREE
    }

    /// Which vertex is the infinite one, if any.
    pub fn infinite_slot(&self) -> Option<usize> {
        self.v.iter().position(|&v| v == INFINITE)
    }
}

/// Why no triangulation was built.
#[derive(Debug, thiserror::Error, PartialEq)]
#[non_exhaustive]
pub enum DelaunayError {
    /// A point has a NaN or infinite coordinate.
    #[error("point {index} has a non-finite coordinate")]
    NonFinite {
        /// Its index.
        index: usize,
    },
    /// The points and their ranks differ in number.
    #[error("{points} points and {ranks} ranks")]
    RankCount {
        /// Points given.
        points: usize,
        /// Ranks given.
        ranks: usize,
    },
    /// The points span no volume.
    #[error("the {distinct} distinct points are all {shape}: no 3-D triangulation exists (a flat or linear cloud needs a 2-D method)")]
    Degenerate {
        /// Distinct points.
        distinct: usize,
        /// What they all lie on (a point, a line, a plane).
        shape: &'static str,
    },
    /// The triangulation would need more points or cells than it can address.
    #[error("more than {limit} points or cells for one triangulation")]
    TooLarge {
        /// The limit.
        limit: usize,
    },
    /// A point location walk did not end: the triangulation is inconsistent.
    #[error("the point location walk did not end (inconsistent triangulation)")]
    WalkStuck,
}

/// Scratch of one insertion, kept between insertions so the loop does not
/// allocate.
#[derive(Default)]
struct Scratch {
    stack: Vec<u32>,
    conflict: Vec<u32>,
    /// Conflict cell and face index of each face of the cavity's boundary.
    boundary: Vec<(u32, u8)>,
    /// The new cells: slot, vertices (with `p` at `slot_of_p`).
    created: Vec<(u32, [u32; 4], u8)>,
    edges: EdgeTable,
}

/// Pairs the new cells' faces through `p`: each edge of the cavity's
/// boundary is met exactly twice.
#[derive(Default)]
struct EdgeTable {
    keys: Vec<u64>,
    values: Vec<u32>,
    generation: Vec<u32>,
    current: u32,
}

impl EdgeTable {
    fn reset(&mut self, edges: usize) {
        let size = (edges * 2).next_power_of_two().max(64);
        if size > self.keys.len() {
            self.keys = vec![0; size];
            self.values = vec![0; size];
            self.generation = vec![0; size];
            self.current = 0;
        }
        self.current = self.current.wrapping_add(1);
        if self.current == 0 {
            self.generation.iter_mut().for_each(|g| *g = 0);
            self.current = 1;
        }
    }

    /// Returns the value stored under `key` by its first meeting, or stores
    /// `value` and returns `None`.
    fn meet(&mut self, key: u64, value: u32) -> Option<u32> {
        let mask = self.keys.len() - 1;
        let mut i = (key.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 40) as usize & mask;
        loop {
            if self.generation[i] != self.current {
                self.generation[i] = self.current;
                self.keys[i] = key;
                self.values[i] = value;
                return None;
            }
            if self.keys[i] == key {
                return Some(self.values[i]);
            }
            i = (i + 1) & mask;
        }
    }
}

/// The Delaunay triangulation of a point set; ranks (input ids) break ties,
/// see `super::predicates`. Vertices are numbered in insertion order (so
/// the cells of one region address nearby memory) and keep their position,
/// rank and index in the input.
pub struct Delaunay {
    pos: Vec<DVec3>,
    rank: Vec<u64>,
    input: Vec<u32>,
    cells: Vec<Cell>,
    free: Vec<u32>,
    /// A cell of each vertex.
    vertex_cell: Vec<u32>,
    /// `(duplicate, kept)` input indices.
    duplicates: Vec<(u32, u32)>,
    inserted: usize,
    rng: u32,
    scratch: Scratch,
}

impl Delaunay {
    /// Triangulates `points` (duplicates are left out, see
    /// [`Delaunay::duplicates`]).
    pub fn new(points: &[DVec3], ranks: &[u64]) -> Result<Self, DelaunayError> {
        if points.len() != ranks.len() {
            return Err(DelaunayError::RankCount {
                points: points.len(),
                ranks: ranks.len(),
            });
        }
        if points.len() >= MAX_CELLS / 8 {
            return Err(DelaunayError::TooLarge {
                limit: MAX_CELLS / 8,
            });
        }
        if let Some(index) = points.iter().position(|p| !p.is_finite()) {
            return Err(DelaunayError::NonFinite { index });
        }
        let InsertionOrder { order, duplicates } = insertion_order(points, ranks);
        let mut d = Delaunay {
            pos: order.iter().map(|&i| points[i as usize]).collect(),
            rank: order.iter().map(|&i| ranks[i as usize]).collect(),
            input: order,
            cells: Vec::with_capacity(points.len() * 7 + 16),
            free: Vec::new(),
            vertex_cell: Vec::new(),
            duplicates,
            inserted: 0,
            rng: 0x2545_F491,
            scratch: Scratch::default(),
        };
        let first = d.first_tetrahedron()?;
        let mut hint = 0;
        for p in 0..d.pos.len() as u32 {
            if first.contains(&p) {
                continue;
            }
            hint = d.insert(p, hint)?;
        }
        d.index_vertices();
        Ok(d)
    }

    /// Vertex positions, by vertex number.
    pub fn points(&self) -> &[DVec3] {
        &self.pos
    }

    /// Vertex ranks (input ids), by vertex number.
    pub fn ranks(&self) -> &[u64] {
        &self.rank
    }

    /// Index in the input of vertex `v`.
    pub fn input_index(&self, v: u32) -> u32 {
        self.input[v as usize]
    }

    /// Every cell slot, free ones included (see [`Cell::is_free`]).
    pub fn cell_slots(&self) -> &[Cell] {
        &self.cells
    }

    /// Cell `c` (live or free).
    pub fn cell(&self, c: u32) -> &Cell {
        &self.cells[c as usize]
    }

    /// Live cells, finite and infinite.
    pub fn cell_count(&self) -> usize {
        self.cells.len() - self.free.len()
    }

    /// Distinct points inserted (all but the duplicates).
    pub fn vertex_count(&self) -> usize {
        self.inserted
    }

    /// `(duplicate, kept)` pairs of equal points, as input indices; the
    /// duplicate is not a vertex.
    pub fn duplicates(&self) -> &[(u32, u32)] {
        &self.duplicates
    }

    /// A live cell with vertex `v`.
    pub fn vertex_cell(&self, v: u32) -> u32 {
        self.vertex_cell[v as usize]
    }

    /// Bytes held by the structure (capacity, not length), for reports.
    pub fn heap_bytes(&self) -> usize {
        self.cells.capacity() * std::mem::size_of::<Cell>()
            + self.pos.capacity() * 24
            + self.rank.capacity() * 8
            + self.input.capacity() * 4
            + self.free.capacity() * 4
            + self.vertex_cell.capacity() * 4
            + self.duplicates.capacity() * 8
    }

    fn pos(&self, v: u32) -> DVec3 {
        self.pos[v as usize]
    }

    fn rank(&self, v: u32) -> u64 {
        self.rank[v as usize]
    }

    /// Four non-coplanar vertices, made into one positive cell and its four
    /// hull cells: the first two, the first not collinear with them, the
    /// first not coplanar with those three.
    fn first_tetrahedron(&mut self) -> Result<[u32; 4], DelaunayError> {
        let distinct = self.pos.len();
        let degenerate = |shape| DelaunayError::Degenerate { distinct, shape };
        if distinct < 2 {
            return Err(degenerate("one point"));
        }
        let (pa, pb) = (self.pos[0], self.pos[1]);
        let c = (2..distinct)
            .find(|&k| !collinear(pa, pb, self.pos[k]))
            .ok_or_else(|| degenerate("collinear"))?;
        let pc = self.pos[c];
        let d = (2..distinct)
            .find(|&k| orient(pa, pb, pc, self.pos[k]) != 0.0)
            .ok_or_else(|| degenerate("coplanar"))?;
        let (c, d) = (c as u32, d as u32);
        let mut v = [0, 1, c, d];
        if orient(pa, pb, pc, self.pos(d)) < 0.0 {
            v.swap(0, 1);
        }
        let mut cells = vec![v];
        for j in 0..4 {
            let mut w = v;
            w[j] = INFINITE;
            w.swap((j + 1) & 3, (j + 2) & 3);
            cells.push(w);
        }
        for w in &cells {
            self.push_cell(Cell { v: *w, n: [0; 4] })?;
        }
        self.link_by_faces(5);
        self.inserted = 4;
        Ok([0, 1, c, d])
    }

    /// Links the first `count` cells by matching faces (for the first five).
    fn link_by_faces(&mut self, count: usize) {
        let face = |c: &Cell, j: usize| {
            let mut f: Vec<u32> = (0..4).filter(|&k| k != j).map(|k| c.v[k]).collect();
            f.sort_unstable();
            f
        };
        for a in 0..count {
            for b in 0..count {
                for (i, j) in (0..4).flat_map(|i| (0..4).map(move |j| (i, j))) {
                    if a != b && face(&self.cells[a], i) == face(&self.cells[b], j) {
                        self.cells[a].n[i] = (b as u32) << 2 | j as u32;
                    }
                }
            }
        }
    }

    fn push_cell(&mut self, cell: Cell) -> Result<u32, DelaunayError> {
        if self.cells.len() >= MAX_CELLS {
            return Err(DelaunayError::TooLarge { limit: MAX_CELLS });
        }
        self.cells.push(cell);
        Ok(self.cells.len() as u32 - 1)
    }

    fn insert(&mut self, p: u32, hint: u32) -> Result<u32, DelaunayError> {
        let start = self.locate(self.pos(p), hint)?;
        self.dig_cavity(p, start);
        self.inserted += 1;
        self.fill_cavity(p)
    }

    /// Visibility walk from `start` to a cell in conflict with `q`: a finite
    /// cell containing it, or a hull cell it lies strictly beyond. The face
    /// tried first rotates pseudo-randomly (a stochastic walk, which ends on
    /// any triangulation); a step limit turns a corrupt structure into an
    /// error rather than a hang.
    fn locate(&mut self, q: DVec3, start: u32) -> Result<u32, DelaunayError> {
        let mut c = start;
        if let Some(k) = self.cells[c as usize].infinite_slot() {
            c = self.cells[c as usize].n[k] >> 2;
        }
        let mut from = INFINITE;
        for _ in 0..4 * self.cells.len() + 64 {
            let cell = self.cells[c as usize];
            if cell.v.contains(&INFINITE) {
                return Ok(c);
            }
            let v = cell.v.map(|v| self.pos(v));
            self.rng ^= self.rng << 13;
            self.rng ^= self.rng >> 17;
            self.rng ^= self.rng << 5;
            let s = self.rng as usize;
            let mut next = None;
            for t in 0..4 {
                let j = (s + t) & 3;
                let nb = cell.n[j] >> 2;
                if nb == from {
                    continue;
                }
                let mut w = v;
                w[j] = q;
                if orient(w[0], w[1], w[2], w[3]) < 0.0 {
                    next = Some(nb);
                    break;
                }
            }
            match next {
                Some(nb) => {
                    from = c;
                    c = nb;
                }
                None => return Ok(c),
            }
        }
        Err(DelaunayError::WalkStuck)
    }

    /// Whether cell `c` is in conflict with point `p`: `p` strictly inside
    /// its circumsphere, or for a hull cell strictly beyond its hull face
    /// (or on its plane inside its circumcircle), ties by perturbation.
    pub(crate) fn conflicts(&self, c: u32, p: u32) -> bool {
        let cell = &self.cells[c as usize];
        let q = self.pos(p);
        match cell.infinite_slot() {
            None => in_sphere_perturbed(
                cell.v.map(|v| self.pos(v)),
                || cell.v.map(|v| self.rank(v)),
                q,
                self.rank(p),
            ),
            Some(k) => self.conflicts_hull(cell, k, p),
        }
    }

    fn conflicts_hull(&self, cell: &Cell, k: usize, p: u32) -> bool {
        let q = self.pos(p);
        let w = cell.v.map(|v| if v == INFINITE { q } else { self.pos(v) });
        let o = orient(w[0], w[1], w[2], w[3]);
        if o != 0.0 {
            return o > 0.0;
        }
        let f = [(k + 1) & 3, (k + 2) & 3, (k + 3) & 3].map(|i| cell.v[i]);
        in_circle_perturbed(
            f.map(|v| self.pos(v)),
            f.map(|v| self.rank(v)),
            q,
            self.rank(p),
        )
    }

    /// Marks the conflict region of `p` from `start` and lists its boundary.
    fn dig_cavity(&mut self, p: u32, start: u32) {
        let mut s = std::mem::take(&mut self.scratch);
        s.stack.clear();
        s.conflict.clear();
        s.boundary.clear();
        self.cells[start as usize].v[0] |= IN;
        s.stack.push(start);
        s.conflict.push(start);
        while let Some(c) = s.stack.pop() {
            for j in 0..4 {
                let nb = self.cells[c as usize].n[j] >> 2;
                let v = self.cells[nb as usize].v;
                if v[0] & IN != 0 {
                    continue;
                }
                if v[1] & OUT == 0 {
                    if self.conflicts(nb, p) {
                        self.cells[nb as usize].v[0] |= IN;
                        s.stack.push(nb);
                        s.conflict.push(nb);
                        continue;
                    }
                    self.cells[nb as usize].v[1] |= OUT;
                }
                s.boundary.push((c, j as u8));
            }
        }
        self.scratch = s;
    }

    /// Replaces the conflict cells by the cone from `p` over the cavity's
    /// boundary; returns one new cell.
    fn fill_cavity(&mut self, p: u32) -> Result<u32, DelaunayError> {
        let mut s = std::mem::take(&mut self.scratch);
        s.created.clear();
        // Every new cell is read off its conflict cell before any slot is
        // reused.
        let mut outer = Vec::with_capacity(0);
        std::mem::swap(&mut outer, &mut s.stack);
        outer.clear();
        for &(c, j) in &s.boundary {
            let cell = &self.cells[c as usize];
            let mut v = cell.v;
            v[0] &= !IN;
            v[j as usize] = p;
            outer.push(cell.n[j as usize]);
            s.created.push((0, v, j));
        }
        let mut reuse = s.conflict.iter().copied();
        for (k, &out) in outer.iter().enumerate() {
            let slot = match reuse.next().or_else(|| self.free.pop()) {
                Some(slot) => slot,
                None => self.push_cell(Cell {
                    v: [FREE; 4],
                    n: [0; 4],
                })?,
            };
            let (_, v, j) = s.created[k];
            s.created[k].0 = slot;
            let mut n = [0u32; 4];
            n[j as usize] = out;
            self.cells[slot as usize] = Cell { v, n };
            let (oc, of) = (out >> 2, out & 3);
            let o = &mut self.cells[oc as usize];
            o.n[of as usize] = slot << 2 | j as u32;
            o.v[1] &= !OUT;
        }
        // Fewer new cells than conflict cells cannot happen (a cavity with
        // F boundary faces had F - 2 cells); free any left all the same.
        for slot in reuse {
            self.cells[slot as usize].v = [FREE; 4];
            self.free.push(slot);
        }
        s.edges.reset(s.created.len() * 3 / 2);
        for &(slot, v, j) in &s.created {
            for (k, &[x, y]) in EDGE_OF[j as usize].iter().enumerate() {
                if k == j as usize {
                    continue;
                }
                let (a, b) = (v[x], v[y]);
                let key = (a.min(b) as u64) << 32 | a.max(b) as u64;
                let here = slot << 2 | k as u32;
                if let Some(there) = s.edges.meet(key, here) {
                    self.cells[slot as usize].n[k] = there;
                    self.cells[(there >> 2) as usize].n[(there & 3) as usize] = here;
                }
            }
        }
        let last = s.created.last().map_or(0, |c| c.0);
        s.stack = outer;
        self.scratch = s;
        Ok(last)
    }

    fn index_vertices(&mut self) {
        self.vertex_cell = vec![INFINITE; self.pos.len()];
        for (c, cell) in self.cells.iter().enumerate() {
            if cell.is_free() {
                continue;
            }
            for &v in &cell.v {
                if v != INFINITE {
                    self.vertex_cell[v as usize] = c as u32;
                }
            }
        }
    }

    /// The live cells incident to vertex `v`, appended to `out` (which is
    /// cleared first): a search over neighbours that keep `v`.
    pub fn star(&self, v: u32, out: &mut Vec<u32>) {
        // Stars are small (about 26 cells): a stack table of 256 slots
        // (open addressing) marks visited cells; larger stars (cospherical
        // or degenerate inputs) fall back to scanning `out`.
        const SLOTS: usize = 256;
        let mut seen = [u32::MAX; SLOTS];
        let mut visit = |c: u32, out: &mut Vec<u32>| {
            if out.len() >= SLOTS / 2 {
                if !out.contains(&c) {
                    out.push(c);
                }
                return;
            }
            let mut h = (c.wrapping_mul(0x9E37_79B9) >> 24) as usize;
            loop {
                if seen[h] == c {
                    return;
                }
                if seen[h] == u32::MAX {
                    seen[h] = c;
                    out.push(c);
                    return;
                }
                h = (h + 1) & (SLOTS - 1);
            }
        };
        out.clear();
        visit(self.vertex_cell(v), out);
        let mut i = 0;
        while i < out.len() {
            let cell = self.cells[out[i] as usize];
            for j in 0..4 {
                if cell.v[j] != v {
                    visit(cell.n[j] >> 2, out);
                }
            }
            i += 1;
        }
    }
}
