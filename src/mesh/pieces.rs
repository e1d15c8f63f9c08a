//! Dropping a mesh's small connected pieces while it streams out: a
//! [`MeshWriter`] behind a filter that keeps every vertex and triangle in
//! raw scratch files, joins the vertices of each triangle in disjoint sets,
//! and at the end replays only the pieces with at least a given share of
//! the largest piece's triangles, with vertices renumbered.
//!
//! Why: a closed scan (`reconstruct --closed`) should come out as the
//! object, but a few lattice cubes around a stray cluster of samples (VRIP
//! debris inside the dragon, noise) close into pieces of their own.
//! MeshLab's "remove isolated pieces" is the usual after-the-fact tool; here
//! it costs a replay of the scratch files at the end, and the per-vertex
//! state (the sets' parents, then the triangle counts that become the new
//! numbers) lives in scratch files too, behind caches of a fixed size
//! (`super::paged`), so that `--mem` holds at any mesh size. With a share
//! of 0 the filter passes everything straight through and keeps nothing.
//!
//! Whether the pieces kept are closed, and enclose a positive volume, is
//! the writer's audit's to count ([`super::audit`]), on the mesh as
//! written: a `--closed` run promises it ([`super::Promise::CLOSED`]).

use super::paged::{ExternalSets, PagedU32, TABLE_BYTES_PER_ELEMENT};
use super::scratch::scratch_beside;
use super::write::Written;
use super::{MeshError, MeshWriter};
use crate::io::IoError;
use glam::DVec3;
use std::fs::File;
use std::io::{BufReader, BufWriter, Read, Seek, SeekFrom, Write};

/// Memory per mesh vertex: the page tables of the parents' and the
/// counts' files (the pages themselves are in the fixed-size caches).
pub const BYTES_PER_VERTEX: f64 = 2.0 * TABLE_BYTES_PER_ELEMENT;

/// Cache of each per-vertex file: 8 MiB (2048 pages) holds a tile's
/// vertices and the seam pages it reaches back to.
const CACHE_BYTES: usize = 8 << 20;

/// Items replayed into the writer at a time.
const BATCH: usize = 1 << 16;

/// What the filter dropped.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PieceReport {
    /// Connected pieces left out.
    pub pieces_dropped: u64,
    /// Triangles of those pieces.
    pub triangles_dropped: u64,
}

/// A [`MeshWriter`] that drops the small pieces of the mesh written through it (see the module doc).
pub struct PieceFilter {
    out: MeshWriter,
    spool: Option<Spool>,
}

/// The raw mesh so far, and which vertices are joined.
struct Spool {
    min_share: f64,
    vertices: BufWriter<File>,
    faces: BufWriter<File>,
    vertex_count: u64,
    sets: ExternalSets,
    /// The counts' file, opened with the others so a full disk shows early.
    counts: File,
}

impl PieceFilter {
    /// Keeps the pieces with at least `min_share` (0..=1) of the largest
    /// piece's triangles; 0 keeps everything and spools nothing.
    pub fn new(out: MeshWriter, min_share: f64) -> Result<Self, MeshError> {
        if min_share <= 0.0 {
            return Ok(PieceFilter { out, spool: None });
        }
        let spool = Spool::create(&out, min_share)?;
        Ok(PieceFilter {
            spool: Some(spool),
            out,
        })
    }

    fn os(&self, e: std::io::Error) -> MeshError {
        MeshError::Io(IoError::os(self.out.path(), e))
    }

    /// As [`MeshWriter::add_vertices`]; the checks happen on replay.
    pub fn add_vertices(&mut self, vertices: &[DVec3]) -> Result<u32, MeshError> {
        let Some(spool) = &mut self.spool else {
            return self.out.add_vertices(vertices);
        };
        let first = spool.vertex_count;
        let count = first + vertices.len() as u64;
        // u32::MAX itself marks a dropped vertex on replay.
        if count >= u32::MAX as u64 {
            return Err(MeshError::TooManyVertices {
                path: self.out.path().to_path_buf(),
                count,
                limit: u32::MAX as u64 - 1,
            });
        }
        let written = spool.add_vertices(vertices);
        written.map_err(|e| self.os(e))?;
        Ok(first as u32)
    }

    /// As [`MeshWriter::add_triangles`].
    pub fn add_triangles(&mut self, triangles: &[[u32; 3]]) -> Result<(), MeshError> {
        let Some(spool) = &mut self.spool else {
            return self.out.add_triangles(triangles);
        };
        let written = spool.add_triangles(triangles);
        written.map_err(|e| self.os(e))
    }

    /// Replays the kept pieces and completes the file; returns what the
    /// writer wrote (the counts and the audit) and what was dropped.
    pub fn finish(self) -> Result<(Written, PieceReport), MeshError> {
        let PieceFilter { mut out, spool } = self;
        let Some(spool) = spool else {
            return Ok((out.finish()?, PieceReport::default()));
        };
        let report = spool.replay(&mut out)?;
        Ok((out.finish()?, report))
    }
}

/// A scratch file beside `out`'s file.
fn scratch(out: &MeshWriter) -> Result<File, MeshError> {
    scratch_beside(out.path()).map_err(|e| MeshError::Io(IoError::os(out.path(), e)))
}

impl Spool {
    fn create(out: &MeshWriter, min_share: f64) -> Result<Self, MeshError> {
        let buffered = |f| BufWriter::with_capacity(1 << 20, f);
        Ok(Spool {
            min_share,
            vertices: buffered(scratch(out)?),
            faces: buffered(scratch(out)?),
            vertex_count: 0,
            sets: ExternalSets::new(scratch(out)?, CACHE_BYTES),
            counts: scratch(out)?,
        })
    }

    fn add_vertices(&mut self, vertices: &[DVec3]) -> std::io::Result<()> {
        for p in vertices {
            for c in p.to_array() {
                self.vertices.write_all(&c.to_le_bytes())?;
            }
        }
        self.vertex_count += vertices.len() as u64;
        self.sets.grow(self.vertex_count);
        Ok(())
    }

    fn add_triangles(&mut self, triangles: &[[u32; 3]]) -> std::io::Result<()> {
        for t in triangles {
            for i in t {
                self.faces.write_all(&i.to_le_bytes())?;
            }
            // An index past the vertices (a caller's bug) gets a set of its
            // own here and an out-of-range number on replay, where the
            // writer names it.
            self.sets.grow(t.iter().max().map_or(0, |&m| m as u64 + 1));
            self.sets.union(t[0] as u64, t[1] as u64)?;
            self.sets.union(t[0] as u64, t[2] as u64)?;
        }
        Ok(())
    }

    /// Writes the kept vertices and triangles into `out`.
    fn replay(mut self, out: &mut MeshWriter) -> Result<PieceReport, MeshError> {
        let path = out.path().to_path_buf();
        let os = |e| MeshError::Io(IoError::os(&path, e));
        let mut faces = rewind(self.faces).map_err(os)?;
        // Triangles per piece, at the piece's root (its smallest vertex).
        let mut count = PagedU32::new(self.counts, CACHE_BYTES);
        let mut largest = 0u32;
        try_for_each_record::<12, std::io::Error>(&mut faces, |r| {
            let a = u32::from_le_bytes([r[0], r[1], r[2], r[3]]);
            let root = self.sets.find(a as u64)?;
            let c = count.get(root)?.saturating_add(1);
            largest = largest.max(c);
            count.set(root, c)
        })
        .map_err(os)?;
        let least = (self.min_share * largest as f64).ceil() as u32;
        let mut report = PieceReport::default();
        // A root comes before its members, so `count` can turn into the new
        // numbering as it goes: at a root its own count is still there; at
        // a member the root's new number is (u32::MAX: dropped).
        let mut next = 0u32;
        for v in 0..self.sets.len() {
            let root = self.sets.find(v).map_err(os)?;
            let kept = if root == v {
                let c = count.get(v).map_err(os)?;
                let keep = c >= least;
                if !keep && c > 0 {
                    report.pieces_dropped += 1;
                    report.triangles_dropped += c as u64;
                }
                keep
            } else {
                count.get(root).map_err(os)? != u32::MAX
            };
            let number = match kept {
                false => u32::MAX,
                true if v >= self.vertex_count => u32::MAX - 1,
                true => {
                    next += 1;
                    next - 1
                }
            };
            count.set(v, number).map_err(os)?;
        }
        let mut renumbered = count;
        let mut vertices = rewind(self.vertices).map_err(os)?;
        let mut batch = Vec::with_capacity(BATCH);
        let mut v = 0u64;
        try_for_each_record::<24, Replay>(&mut vertices, |r| {
            if renumbered.get(v)? != u32::MAX {
                let c = |i: usize| f64::from_le_bytes(r[i..i + 8].try_into().unwrap_or([0; 8]));
                batch.push(DVec3::new(c(0), c(8), c(16)));
            }
            v += 1;
            if batch.len() == BATCH {
                out.add_vertices(&batch).map_err(Replay::Mesh)?;
                batch.clear();
            }
            Ok(())
        })
        .map_err(|e| e.into_mesh(&path))?;
        out.add_vertices(&batch)?;
        faces.seek(SeekFrom::Start(0)).map_err(os)?;
        let mut kept = Vec::with_capacity(BATCH);
        try_for_each_record::<12, Replay>(&mut faces, |r| {
            let i = |k: usize| u32::from_le_bytes([r[k], r[k + 1], r[k + 2], r[k + 3]]);
            let mut t = [0u32; 3];
            for (slot, x) in t.iter_mut().zip([i(0), i(4), i(8)]) {
                *slot = renumbered.get(x as u64)?;
            }
            if t[0] != u32::MAX {
                kept.push(t);
            }
            if kept.len() == BATCH {
                out.add_triangles(&kept).map_err(Replay::Mesh)?;
                kept.clear();
            }
            Ok(())
        })
        .map_err(|e| e.into_mesh(&path))?;
        out.add_triangles(&kept)?;
        Ok(report)
    }
}

/// A failure while replaying into the writer: the scratch files' or the
/// writer's own.
enum Replay {
    Io(std::io::Error),
    Mesh(MeshError),
}

impl From<std::io::Error> for Replay {
    fn from(e: std::io::Error) -> Self {
        Replay::Io(e)
    }
}

impl Replay {
    fn into_mesh(self, path: &std::path::Path) -> MeshError {
        match self {
            Replay::Io(e) => MeshError::Io(IoError::os(path, e)),
            Replay::Mesh(e) => e,
        }
    }
}

fn rewind(w: BufWriter<File>) -> std::io::Result<BufReader<File>> {
    let mut f = w.into_inner().map_err(|e| e.into_error())?;
    f.seek(SeekFrom::Start(0))?;
    Ok(BufReader::with_capacity(1 << 20, f))
}

/// Calls `f` on each record of `N` bytes until the end or `f`'s first error.
fn try_for_each_record<const N: usize, E: From<std::io::Error>>(
    r: &mut BufReader<File>,
    mut f: impl FnMut(&[u8; N]) -> Result<(), E>,
) -> Result<(), E> {
    let mut record = [0u8; N];
    loop {
        match r.read_exact(&mut record) {
            Ok(()) => f(&record)?,
            Err(e) if e.kind() == std::io::ErrorKind::UnexpectedEof => return Ok(()),
            Err(e) => return Err(e.into()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::read_mesh_any;
    use crate::mesh::audit::{incomplete_path, Failure, Promise};
    use crate::mesh::quality::quality;
    use crate::mesh::shapes::icosphere;
    use crate::mesh::{write_mesh, Mesh, MeshFormat};

    /// How the two spheres of [`write_two_spheres`] are written.
    #[derive(Clone, Copy)]
    struct Spheres {
        min_share: f64,
        /// What the writer promises.
        promise: Promise,
        /// Wind the small sphere inward.
        small_inward: bool,
    }

    /// A big sphere (1280 triangles), a small far one (20) written between its halves (so the
    /// kept vertices need renumbering), in batches as a stitcher would.
    fn write_two_spheres(path: &std::path::Path, min_share: f64) -> PieceReport {
        let how = Spheres {
            min_share,
            promise: Promise::NOTHING,
            small_inward: false,
        };
        write_spheres(path, how).unwrap().1
    }

    fn write_spheres(
        path: &std::path::Path,
        how: Spheres,
    ) -> Result<(Written, PieceReport), MeshError> {
        let big = icosphere(3);
        let small = icosphere(0);
        let writer = MeshWriter::create(path, MeshFormat::PlyBinary)
            .unwrap()
            .promising(how.promise);
        let mut filter = PieceFilter::new(writer, how.min_share).unwrap();
        let (half, rest) = big.triangles.split_at(big.triangles.len() / 2);
        filter.add_vertices(&big.vertices).unwrap();
        filter.add_triangles(half).unwrap();
        let far: Vec<DVec3> = small
            .vertices
            .iter()
            .map(|p| *p * 0.1 + DVec3::splat(5.0))
            .collect();
        let first = filter.add_vertices(&far).unwrap();
        let shifted: Vec<[u32; 3]> = small
            .triangles
            .iter()
            .map(|t| t.map(|i| i + first))
            .map(|[a, b, c]| {
                if how.small_inward {
                    [a, c, b]
                } else {
                    [a, b, c]
                }
            })
            .collect();
        filter.add_triangles(&shifted).unwrap();
        filter.add_triangles(rest).unwrap();
        filter.finish()
    }

    #[test]
    fn kept_pieces_wound_outward_keep_the_closed_promise() {
        let dir = tempfile::tempdir().unwrap();
        let (checked, plain) = (dir.path().join("a.ply"), dir.path().join("b.ply"));
        for (share, kept) in [(0.0, 2), (0.05, 1)] {
            let how = Spheres {
                min_share: share,
                promise: Promise::CLOSED,
                small_inward: false,
            };
            let (written, _) = write_spheres(&checked, how).unwrap();
            let a = written.audit;
            assert_eq!((a.components, a.closed_components), (kept, kept));
            assert_eq!(a.inward_components, 0, "share {share}");
            // The promise changes nothing written.
            write_two_spheres(&plain, share);
            assert!(std::fs::read(&checked).unwrap() == std::fs::read(&plain).unwrap());
        }
    }

    #[test]
    fn an_inward_piece_breaks_the_closed_promise_and_is_written_incomplete() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.ply");
        let how = Spheres {
            min_share: 0.0,
            promise: Promise::CLOSED,
            small_inward: true,
        };
        match write_spheres(&path, how) {
            Err(MeshError::PromiseBroken {
                failures, written, ..
            }) => {
                let [Failure::Inward {
                    components: 1,
                    smallest,
                }] = failures[..]
                else {
                    panic!("{failures:?}")
                };
                // The small sphere's volume, 0.1^3 of an icosahedron's 2.54.
                assert!(smallest < -0.002 && smallest > -0.003, "{smallest}");
                assert_eq!(written, incomplete_path(&path));
            }
            other => panic!("{other:?}"),
        }
        assert!(!path.exists());
        let names: Vec<_> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names, ["m.incomplete.ply"]);
        // The incomplete file holds the whole mesh, inward piece and all.
        let (v, t) = read_mesh_any(&incomplete_path(&path)).unwrap();
        assert_eq!((v.len(), t.len()), (642 + 12, 1280 + 20));
        // Dropped as a small piece, it is not checked.
        let dropped = Spheres {
            min_share: 0.05,
            ..how
        };
        let (written, _) = write_spheres(&path, dropped).unwrap();
        assert_eq!(written.audit.closed_components, 1);
    }

    #[test]
    fn a_small_piece_is_dropped_and_the_rest_renumbered() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.ply");
        let report = write_two_spheres(&path, 0.05);
        let small = icosphere(0).triangles.len() as u64;
        assert_eq!(
            report,
            PieceReport {
                pieces_dropped: 1,
                triangles_dropped: small,
            }
        );
        let (vertices, triangles) = read_mesh_any(&path).unwrap();
        let big = icosphere(3);
        assert_eq!(vertices, big.vertices);
        assert_eq!(triangles, big.triangles);
        let q = quality(&Mesh::new(vertices, triangles));
        assert!(q.watertight && q.components == 1 && q.unreferenced_vertices == 0);
    }

    #[test]
    fn a_share_of_zero_passes_everything_through() {
        let dir = tempfile::tempdir().unwrap();
        let (kept, direct) = (dir.path().join("a.ply"), dir.path().join("b.ply"));
        assert_eq!(write_two_spheres(&kept, 0.0), PieceReport::default());
        let (vertices, triangles) = read_mesh_any(&kept).unwrap();
        write_mesh(
            &direct,
            &Mesh::new(vertices, triangles),
            MeshFormat::PlyBinary,
        )
        .unwrap();
        assert_eq!(
            std::fs::read(&kept).unwrap(),
            std::fs::read(&direct).unwrap()
        );
        // And a share of 1 keeps only the largest piece.
        assert_eq!(write_two_spheres(&kept, 1.0).pieces_dropped, 1);
    }
}
