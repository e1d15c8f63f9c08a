//! The mesh audit: what a written mesh is, counted while it streams out
//! through a [`super::MeshWriter`], in memory that does not grow with the
//! mesh. This module owns the report ([`MeshAudit`]), what a run promises
//! of its mesh ([`Promise`]) and how a promise fails ([`Failure`]), and the
//! streaming counter the writer feeds (`Auditor`); a mesh in memory is fed
//! to it by `audit_mesh`.
//!
//! Counted, with [`super::quality`]'s definitions (the triangles with three
//! distinct indices take part; a triangle with a repeated index is counted
//! and left out of everything else):
//! - edges used by one triangle (boundary), by more than two
//!   (non-manifold), by two running it the same way (inconsistent);
//! - non-manifold vertices: the triangles round a vertex form more than one
//!   fan (its link, the graph of each triangle's other two corners, has
//!   more than one connected component). A vertex on a non-manifold edge
//!   whose link is connected counts as manifold, as in `quality`;
//! - boundary loops: the connected components of the graph of the boundary
//!   edges over the vertices. `quality` first splits every non-manifold
//!   vertex into one copy per fan, so where two loops touch at a bow-tie
//!   vertex it counts two and this counts one: the two agree whenever there
//!   is no non-manifold vertex;
//! - connected components by shared vertices; each is closed when it has no
//!   boundary edge, no non-manifold edge and no non-manifold vertex (as
//!   `quality`'s), and a closed one's signed volume is the sum of
//!   `a . (b x c) / 6` over its triangles, positive when wound outward;
//! - the Euler characteristic V - E + F over the referenced vertices.
//!
//! How, for billions of triangles: each triangle `(a, b, c)` gives three
//! corner records `(v, prev, next)` (`(a, c, b)`, `(b, a, c)`, `(c, b, a)`;
//! 12 bytes each), sorted out of core by vertex (`super::runs`: buffers of
//! a fixed size sorted and written as runs to a scratch file, merged at
//! the end a vertex's block of each run at a time), so every vertex's
//! corners arrive together, vertices in increasing order. At vertex `v`
//! the corners name every edge `{v, w}` and how often each triangle runs it
//! out of `v` (`next == w`) or into it (`prev == w`): an edge is counted at
//! its smaller vertex, so exactly once, and the link's components are found
//! by a union-find over the few neighbours. A vertex's corners are sorted
//! before they are counted, so every sum is the same whatever the buffer
//! size (the order the runs give them in).
//!
//! Components are disjoint sets over a paged scratch file
//! ([`super::paged::ExternalSets`]), joined as triangles arrive; a set's
//! root is its smallest vertex, so the sweep meets a component first at its
//! root. Positions are spooled (f64, 24 B a vertex) and read back through
//! a page cache; a triangle's triple product is taken at its smallest
//! vertex, in a frame at the first vertex (so the products keep the digits
//! the mesh's size leaves them), and summed into its root's entry of a paged
//! array, which also marks the root open when any of its vertices sees a
//! boundary or non-manifold edge or is itself non-manifold.
//!
//! RAM: the record buffer ([`Sizes::chunk_bytes`], 16 MiB) while the mesh
//! streams, then the merge buffers (16 MiB) and four page caches (14 MiB);
//! per vertex, the caches' page tables (4 B per 1024 vertices each).
//! Scratch disk beside the output: 36 B per triangle (the runs; twice that
//! while a round of merges runs), 24 B per vertex (positions), 4 B per
//! vertex for each set, 9 B per vertex for the sums, 4 B per component.

use super::paged::{Element, ExternalSets, Paged};
use super::runs::{Order, RunSizes, SortedRuns};
use super::scratch::scratch_beside;
use glam::DVec3;
use std::fmt;
use std::fs::File;
use std::io::{self, BufReader, BufWriter, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

/// Scratch disk beside the output per mesh triangle: the runs' 36 B and
/// half a vertex's 41 B (positions 24, the two sets 8, the sums 9), a
/// closed mesh having half as many vertices as triangles. A round of
/// merges (above ~120M triangles) doubles the runs' share.
pub(crate) const SCRATCH_PER_TRIANGLE: f64 = 36.0 + 41.0 / 2.0;

/// What the audit found in a mesh: plain data, serialised into a run's
/// `--report` (see the module doc for the definitions).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct MeshAudit {
    /// Vertices written, referenced or not.
    pub vertices: u64,
    /// Triangles written.
    pub triangles: u64,
    /// Vertices some triangle with three distinct indices uses.
    pub referenced_vertices: u64,
    /// Triangles that use one vertex twice: counted here and left out of
    /// every other count.
    pub repeated_index_triangles: u64,
    /// Distinct undirected edges.
    pub edges: u64,
    /// Edges used by one triangle.
    pub boundary_edges: u64,
    /// Connected components of the boundary edges (see the module doc for
    /// how this differs from `quality`'s at non-manifold vertices).
    pub boundary_loops: u64,
    /// Edges used by more than two triangles.
    pub non_manifold_edges: u64,
    /// Vertices whose triangles form more than one fan.
    pub non_manifold_vertices: u64,
    /// Edges whose two triangles run them the same way.
    pub inconsistent_edges: u64,
    /// Connected components (by shared vertices).
    pub components: u64,
    /// Components without boundary edges, non-manifold edges or vertices.
    pub closed_components: u64,
    /// Closed components whose signed volume is not positive (wound
    /// inward, or flat).
    pub inward_components: u64,
    /// Sum of the closed components' signed volumes.
    pub volume: f64,
    /// The smallest signed volume of a closed component.
    pub smallest_volume: Option<f64>,
    /// The largest signed volume of a closed component.
    pub largest_volume: Option<f64>,
    /// V - E + F over the referenced vertices, the edges and the triangles
    /// with three distinct indices.
    pub euler_characteristic: i64,
}

/// What a run promises of the mesh it writes; the writer checks it at the
/// end and, when it is broken, writes the mesh under an incomplete name
/// ([`incomplete_path`]) and fails with [`super::MeshError::PromiseBroken`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct Promise {
    /// No boundary edge.
    pub watertight: bool,
    /// No edge used by more than two triangles.
    pub manifold_edges: bool,
    /// No vertex whose triangles form more than one fan.
    pub manifold_vertices: bool,
    /// No edge its two triangles run the same way.
    pub consistently_wound: bool,
    /// Every closed component encloses a positive signed volume.
    pub outward: bool,
}

impl Promise {
    /// Nothing is promised: the audit is only counted.
    pub const NOTHING: Promise = Promise {
        watertight: false,
        manifold_edges: false,
        manifold_vertices: false,
        consistently_wound: false,
        outward: false,
    };

    /// A closed surface (`reconstruct --closed`): watertight, manifold,
    /// consistently wound, every component enclosing a positive volume.
    pub const CLOSED: Promise = Promise {
        watertight: true,
        manifold_edges: true,
        manifold_vertices: true,
        consistently_wound: true,
        outward: true,
    };

    /// Every directed edge used once (`reconstruct --method projection`):
    /// no non-manifold edge, no inconsistently wound edge.
    pub const DIRECTED_EDGES: Promise = Promise {
        manifold_edges: true,
        consistently_wound: true,
        ..Promise::NOTHING
    };

    /// What of this promise `audit` breaks (empty: kept).
    pub fn broken_by(&self, audit: &MeshAudit) -> Vec<Failure> {
        let a = audit;
        let mut failures = Vec::new();
        if self.watertight && a.boundary_edges > 0 {
            failures.push(Failure::BoundaryEdges {
                edges: a.boundary_edges,
                loops: a.boundary_loops,
            });
        }
        if self.manifold_edges && a.non_manifold_edges > 0 {
            failures.push(Failure::NonManifoldEdges(a.non_manifold_edges));
        }
        if self.manifold_vertices && a.non_manifold_vertices > 0 {
            failures.push(Failure::NonManifoldVertices(a.non_manifold_vertices));
        }
        if self.consistently_wound && a.inconsistent_edges > 0 {
            failures.push(Failure::InconsistentEdges(a.inconsistent_edges));
        }
        if self.outward && a.inward_components > 0 {
            failures.push(Failure::Inward {
                components: a.inward_components,
                smallest: a.smallest_volume.unwrap_or(0.0),
            });
        }
        failures
    }
}

impl fmt::Display for Promise {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let clauses = [
            (self.watertight, "watertight"),
            (self.manifold_edges, "manifold edges"),
            (self.manifold_vertices, "manifold vertices"),
            (self.consistently_wound, "consistently wound"),
            (self.outward, "closed pieces of positive volume"),
        ];
        let named: Vec<&str> = clauses.iter().filter(|c| c.0).map(|c| c.1).collect();
        match named.is_empty() {
            true => write!(f, "nothing"),
            false => write!(f, "{}", named.join(", ")),
        }
    }
}

/// A clause of a [`Promise`] the mesh breaks, with the counts.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
#[non_exhaustive]
pub enum Failure {
    /// Boundary edges under a watertight promise.
    BoundaryEdges {
        /// Boundary edges.
        edges: u64,
        /// The loops they form.
        loops: u64,
    },
    /// Edges of more than two triangles.
    NonManifoldEdges(u64),
    /// Vertices of more than one fan.
    NonManifoldVertices(u64),
    /// Edges two triangles run the same way.
    InconsistentEdges(u64),
    /// Closed components of a signed volume not above zero.
    Inward {
        /// How many.
        components: u64,
        /// The smallest signed volume among them.
        smallest: f64,
    },
}

impl fmt::Display for Failure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Failure::BoundaryEdges { edges, loops } => write!(
                f,
                "{} in {}",
                counted(edges, "boundary edge"),
                counted(loops, "loop")
            ),
            Failure::NonManifoldEdges(n) => write!(f, "{}", counted(n, "non-manifold edge")),
            Failure::NonManifoldVertices(n) => {
                write!(f, "{}", counted(n, "non-manifold vertex"))
            }
            Failure::InconsistentEdges(n) => {
                write!(f, "{}", counted(n, "inconsistently wound edge"))
            }
            Failure::Inward {
                components,
                smallest,
            } => write!(
                f,
                "{} of signed volume not above zero (down to {smallest:+.4e}: wound inward)",
                counted(components, "closed piece")
            ),
        }
    }
}

/// The failures of a list, joined for an error message.
pub(crate) fn failures_text(failures: &[Failure]) -> String {
    let parts: Vec<String> = failures.iter().map(Failure::to_string).collect();
    parts.join(", ")
}

/// `n` and `what`, plural when `n` is not 1 ("vertex" becomes "vertices").
fn counted(n: u64, what: &str) -> String {
    if n == 1 {
        return format!("1 {what}");
    }
    match what.strip_suffix("vertex") {
        Some(stem) => format!("{n} {stem}vertices"),
        None => format!("{n} {what}s"),
    }
}

/// The compact line a run prints, e.g. `1 piece, closed, 0 non-manifold
/// edges, 0 non-manifold vertices, 0 inconsistently wound, volume
/// +1.234e5, Euler characteristic 2`.
impl fmt::Display for MeshAudit {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let a = self;
        write!(f, "{}", counted(a.components, "piece"))?;
        if a.components > 0 && a.closed_components == a.components {
            write!(f, ", closed")?;
        } else {
            if a.closed_components > 0 {
                write!(f, " ({} closed)", a.closed_components)?;
            }
            write!(
                f,
                ", {} ({})",
                counted(a.boundary_loops, "boundary loop"),
                counted(a.boundary_edges, "boundary edge")
            )?;
        }
        write!(
            f,
            ", {}, {}, {} inconsistently wound",
            counted(a.non_manifold_edges, "non-manifold edge"),
            counted(a.non_manifold_vertices, "non-manifold vertex"),
            a.inconsistent_edges
        )?;
        if a.closed_components > 0 {
            let of = if a.closed_components < a.components {
                " of the closed"
            } else {
                ""
            };
            write!(f, ", volume{of} {:+.3e}", a.volume)?;
            if a.inward_components > 0 {
                write!(
                    f,
                    " ({} inward, down to {:+.3e})",
                    a.inward_components,
                    a.smallest_volume.unwrap_or(0.0)
                )?;
            }
        }
        if a.repeated_index_triangles > 0 {
            write!(
                f,
                ", {} with a repeated index left out",
                counted(a.repeated_index_triangles, "triangle")
            )?;
        }
        write!(f, ", Euler characteristic {}", a.euler_characteristic)
    }
}

/// Where a mesh that breaks its promise is written instead of `path`:
/// `NAME.incomplete.EXT` (`dragon.ply` -> `dragon.incomplete.ply`;
/// `NAME.incomplete` without an extension).
pub fn incomplete_path(path: &Path) -> PathBuf {
    let stem = path.file_stem().unwrap_or(path.as_os_str());
    let mut name = stem.to_os_string();
    name.push(".incomplete");
    if let Some(ext) = path.extension() {
        name.push(".");
        name.push(ext);
    }
    path.with_file_name(name)
}

/// The audit's buffer sizes (tests shrink them to force many runs).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Sizes {
    /// The sort of the corner records.
    pub runs: RunSizes,
    /// Bytes of each page cache (the sets, the positions; the sums and the
    /// loops' sets get a quarter).
    pub cache_bytes: usize,
}

impl Sizes {
    /// 16 MiB of records (1.4M corners: a run per 466k triangles), 256 runs
    /// at once through 64 KiB each, 4 MiB caches (8 for positions).
    pub const DEFAULT: Sizes = Sizes {
        runs: RunSizes::DEFAULT,
        cache_bytes: 4 << 20,
    };
}

/// A corner: the vertex, the corner before it and the corner after it in
/// its triangle. Grouped by vertex.
type Corner = [u32; 3];

/// Corners sorted by their vertex alone.
struct ByVertex;

impl Order<Corner> for ByVertex {
    const GROUPED: bool = true;
    fn key(c: &Corner) -> u64 {
        c[0].into()
    }
}

/// The streaming audit a [`super::MeshWriter`] feeds (see the module doc).
pub(crate) struct Auditor {
    /// The output the scratch files go beside.
    beside: PathBuf,
    sizes: Sizes,
    corners: SortedRuns<Corner, ByVertex>,
    positions: BufWriter<File>,
    /// The first vertex: the frame the volumes are summed in.
    origin: Option<DVec3>,
    vertices: u64,
    triangles: u64,
    repeated: u64,
    sets: ExternalSets,
}

impl Auditor {
    /// An audit whose scratch files go beside `path`.
    pub fn new(path: &Path, sizes: Sizes) -> io::Result<Self> {
        Ok(Auditor {
            beside: path.to_path_buf(),
            sizes,
            corners: SortedRuns::new(path, sizes.runs),
            positions: BufWriter::with_capacity(1 << 16, scratch_beside(path)?),
            origin: None,
            vertices: 0,
            triangles: 0,
            repeated: 0,
            sets: ExternalSets::new(scratch_beside(path)?, sizes.cache_bytes),
        })
    }

    pub fn add_vertices(&mut self, vertices: &[DVec3]) -> io::Result<()> {
        if self.origin.is_none() {
            self.origin = vertices.first().copied();
        }
        let mut bytes = [0u8; 24];
        for p in vertices {
            p.to_array().store(&mut bytes);
            self.positions.write_all(&bytes)?;
        }
        self.vertices += vertices.len() as u64;
        self.sets.grow(self.vertices);
        Ok(())
    }

    pub fn add_triangles(&mut self, triangles: &[[u32; 3]]) -> io::Result<()> {
        for &[a, b, c] in triangles {
            self.triangles += 1;
            if a == b || b == c || a == c {
                self.repeated += 1;
                continue;
            }
            for corner in [[a, c, b], [b, a, c], [c, b, a]] {
                self.corners.push(corner)?;
            }
            self.sets.grow(u64::from(a.max(b).max(c)) + 1);
            self.sets.union(u64::from(a), u64::from(b))?;
            self.sets.union(u64::from(a), u64::from(c))?;
        }
        Ok(())
    }

    /// Merges the runs, sweeps the vertices and returns the counts.
    pub fn finish(mut self) -> io::Result<MeshAudit> {
        let positions = self.positions.into_inner().map_err(|e| e.into_error())?;
        let mut sweep = Sweep {
            audit: MeshAudit {
                vertices: self.vertices,
                triangles: self.triangles,
                repeated_index_triangles: self.repeated,
                ..MeshAudit::default()
            },
            origin: self.origin.unwrap_or(DVec3::ZERO),
            positions: Paged::over(positions, self.vertices, 2 * self.sizes.cache_bytes),
            sums: Paged::new(scratch_beside(&self.beside)?, self.sizes.cache_bytes / 4),
            loops: ExternalSets::new(scratch_beside(&self.beside)?, self.sizes.cache_bytes / 4),
            roots: BufWriter::with_capacity(1 << 16, scratch_beside(&self.beside)?),
            boundary_vertices: 0,
            loop_joins: 0,
            vertex: None,
            link: Vec::new(),
            ends: Vec::new(),
            nodes: Vec::new(),
            parent: Vec::new(),
        };
        sweep.loops.grow(self.vertices);
        let sets = &mut self.sets;
        self.corners.merge(|c| sweep.corner(c, sets))?;
        sweep.close(&mut self.sets)
    }
}

/// A component's running sum, at its root: six times its signed volume
/// (in the frame at the first vertex), and whether it is open.
#[derive(Clone, Copy, Debug, Default)]
struct Sum {
    six_volume: f64,
    open: bool,
}

impl Element for Sum {
    const BYTES: usize = 9;
    fn load(bytes: &[u8]) -> Self {
        Sum {
            six_volume: f64::load(bytes),
            open: bytes[8] != 0,
        }
    }
    fn store(&self, bytes: &mut [u8]) {
        self.six_volume.store(bytes);
        bytes[8] = u8::from(self.open);
    }
}

/// The sweep over the vertices, in increasing order, each with its corners.
struct Sweep {
    audit: MeshAudit,
    origin: DVec3,
    positions: Paged<[f64; 3]>,
    /// Each component's [`Sum`], at its root.
    sums: Paged<Sum>,
    /// Vertices joined by boundary edges.
    loops: ExternalSets,
    /// Each component's root, in increasing order.
    roots: BufWriter<File>,
    boundary_vertices: u64,
    loop_joins: u64,
    /// The vertex being gathered and its corners' (prev, next).
    vertex: Option<u32>,
    link: Vec<(u32, u32)>,
    /// The link's ends: (neighbour, 0 when the triangle runs out of the
    /// vertex to it, 1 when into the vertex from it).
    ends: Vec<(u32, u8)>,
    /// The distinct neighbours, in order, and the local union-find over
    /// them.
    nodes: Vec<u32>,
    parent: Vec<u32>,
}

impl Sweep {
    /// Takes the next corner in sorted order.
    fn corner(&mut self, [v, prev, next]: Corner, sets: &mut ExternalSets) -> io::Result<()> {
        if self.vertex != Some(v) {
            self.vertex_done(sets)?;
            self.vertex = Some(v);
        }
        self.link.push((prev, next));
        Ok(())
    }

    /// Counts the vertex gathered so far, if any.
    fn vertex_done(&mut self, sets: &mut ExternalSets) -> io::Result<()> {
        let Some(v) = self.vertex.take() else {
            return Ok(());
        };
        let a = &mut self.audit;
        a.referenced_vertices += 1;
        // The runs give a vertex's corners in any order: in order, every
        // sum is the same whatever the buffer's size.
        self.link.sort_unstable();
        self.ends.clear();
        for &(prev, next) in &self.link {
            self.ends.extend([(next, 0u8), (prev, 1u8)]);
        }
        self.ends.sort_unstable();
        let (mut on_boundary, mut singular) = (false, false);
        self.parent.clear();
        self.nodes.clear();
        for uses in self.ends.chunk_by(|x, y| x.0 == y.0) {
            let w = uses[0].0;
            self.parent.push(self.parent.len() as u32);
            self.nodes.push(w);
            on_boundary |= uses.len() == 1;
            singular |= uses.len() > 2;
            if w < v {
                continue;
            }
            a.edges += 1;
            match uses.len() {
                1 => {
                    a.boundary_edges += 1;
                    self.loop_joins += u64::from(self.loops.union(v.into(), w.into())?);
                }
                2 => a.inconsistent_edges += u64::from(uses[0].1 == uses[1].1),
                _ => a.non_manifold_edges += 1,
            }
        }
        // The link's components: a corner joins its two neighbours.
        let mut fans = self.parent.len();
        let index = |nodes: &[u32], w: u32| match nodes.binary_search(&w) {
            Ok(i) | Err(i) => i,
        };
        for &(prev, next) in &self.link {
            let (p, n) = (index(&self.nodes, prev), index(&self.nodes, next));
            let (rp, rn) = (root(&mut self.parent, p), root(&mut self.parent, n));
            if rp != rn {
                self.parent[rp.max(rn)] = rp.min(rn) as u32;
                fans -= 1;
            }
        }
        if fans > 1 {
            a.non_manifold_vertices += 1;
            singular = true;
        }
        self.boundary_vertices += u64::from(on_boundary);
        let r = sets.find(v.into())?;
        if r == u64::from(v) {
            a.components += 1;
            self.roots.write_all(&v.to_le_bytes())?;
        }
        let mut sum = self.sums.get(r)?;
        sum.open |= on_boundary || singular;
        let at = |positions: &mut Paged<[f64; 3]>, i: u32| -> io::Result<DVec3> {
            Ok(DVec3::from_array(positions.get(i.into())?))
        };
        let pv = at(&mut self.positions, v)? - self.origin;
        for &(prev, next) in &self.link {
            // The triangle (v, next, prev), once: at its smallest vertex.
            if v < prev && v < next {
                let pn = at(&mut self.positions, next)? - self.origin;
                let pp = at(&mut self.positions, prev)? - self.origin;
                sum.six_volume += pv.dot(pn.cross(pp));
            }
        }
        self.sums.set(r, sum)?;
        self.link.clear();
        Ok(())
    }

    /// Counts the last vertex, then the components from their roots.
    fn close(mut self, sets: &mut ExternalSets) -> io::Result<MeshAudit> {
        self.vertex_done(sets)?;
        let mut a = self.audit;
        a.boundary_loops = self.boundary_vertices - self.loop_joins;
        let faces = a.triangles - a.repeated_index_triangles;
        a.euler_characteristic = a.referenced_vertices as i64 - a.edges as i64 + faces as i64;
        let mut roots = self.roots.into_inner().map_err(|e| e.into_error())?;
        roots.seek(SeekFrom::Start(0))?;
        let mut roots = BufReader::with_capacity(1 << 16, roots);
        let mut word = [0u8; 4];
        for _ in 0..a.components {
            roots.read_exact(&mut word)?;
            let sum = self.sums.get(u32::from_le_bytes(word).into())?;
            if sum.open {
                continue;
            }
            let volume = sum.six_volume / 6.0;
            a.closed_components += 1;
            a.volume += volume;
            a.inward_components += u64::from(volume.is_nan() || volume <= 0.0);
            a.smallest_volume = Some(a.smallest_volume.map_or(volume, |s| s.min(volume)));
            a.largest_volume = Some(a.largest_volume.map_or(volume, |s| s.max(volume)));
        }
        Ok(a)
    }
}

/// The root of `i` in the local union-find `parent` (links point down).
fn root(parent: &mut [u32], mut i: usize) -> usize {
    while parent[i] as usize != i {
        let up = parent[i] as usize;
        parent[i] = parent[up];
        i = up;
    }
    i
}

#[cfg(test)]
#[path = "audit_tests.rs"]
mod tests;
