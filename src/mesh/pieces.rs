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
//! Asked to ([`PieceFilter::requiring_outward`]), it also checks that every
//! piece it keeps encloses a positive volume (its faces wound outward): the
//! sum of the triple products `a . (b x c)` of its triangles' corners, six
//! times the signed volume. Each triangle's term is spooled beside its face
//! (8 bytes) and summed per kept piece on replay, one sum per kept piece in
//! RAM. A piece that fails stops the replay before the output is complete,
//! so no inside-out mesh is ever renamed into place. A piece with a
//! boundary the caller names ([`PieceFilter::open_at`]) encloses nothing
//! and is not checked: its sum depends on the frame (a closed
//! reconstruction of an open sheet is one).

use super::paged::{ExternalSets, PagedU32, TABLE_BYTES_PER_ELEMENT};
use super::write::scratch_beside;
use super::{MeshError, MeshWriter};
use crate::io::IoError;
use glam::DVec3;
use std::collections::HashMap;
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

/// A triangle by vertex indices, with its corners in one frame for the
/// whole mesh (the volume check sums triple products in it: a frame near
/// the mesh keeps them exact).
pub type PlacedTriangle = ([u32; 3], [DVec3; 3]);

/// What the filter dropped, and what it checked.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PieceReport {
    /// Connected pieces left out.
    pub pieces_dropped: u64,
    /// Triangles of those pieces.
    pub triangles_dropped: u64,
    /// Pieces kept whose signed volume was found positive (0 unless the
    /// filter was [`PieceFilter::requiring_outward`]).
    pub pieces_outward: u64,
    /// Pieces kept but not checked: they have a boundary.
    pub pieces_open: u64,
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
    /// Each face's triple product, when volumes are checked.
    volumes: Option<BufWriter<File>>,
    /// A vertex on each boundary loop the caller named: their pieces are
    /// open, so their volumes are not checked.
    open: Vec<u32>,
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

    /// Also checks that every piece kept encloses a positive volume, and
    /// fails with [`MeshError::InwardPieces`] (the output left incomplete)
    /// when one does not. Spools the mesh even with a share of 0, to know
    /// its pieces.
    pub fn requiring_outward(self) -> Result<Self, MeshError> {
        let PieceFilter { out, spool } = self;
        let mut spool = match spool {
            Some(s) => s,
            None => Spool::create(&out, 0.0)?,
        };
        if spool.volumes.is_none() {
            spool.volumes = Some(BufWriter::with_capacity(1 << 20, scratch(&out)?));
        }
        Ok(PieceFilter {
            out,
            spool: Some(spool),
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

    /// Names vertices on boundaries: the pieces holding them are open, and
    /// the volume check passes them over.
    pub fn open_at(&mut self, vertices: &[u32]) {
        if let Some(spool) = &mut self.spool {
            spool.open.extend_from_slice(vertices);
        }
    }

    /// As [`MeshWriter::add_triangles`], each triangle with its corners.
    pub fn add_triangles(&mut self, triangles: &[PlacedTriangle]) -> Result<(), MeshError> {
        let Some(spool) = &mut self.spool else {
            let faces: Vec<[u32; 3]> = triangles.iter().map(|t| t.0).collect();
            return self.out.add_triangles(&faces);
        };
        let written = spool.add_triangles(triangles);
        written.map_err(|e| self.os(e))
    }

    /// Replays the kept pieces and completes the file; returns the vertex
    /// and triangle counts written and what was dropped.
    pub fn finish(self) -> Result<(u64, u64, PieceReport), MeshError> {
        let PieceFilter { mut out, spool } = self;
        let Some(spool) = spool else {
            let (v, t) = out.finish()?;
            return Ok((v, t, PieceReport::default()));
        };
        let report = spool.replay(&mut out)?;
        let (v, t) = out.finish()?;
        Ok((v, t, report))
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
            volumes: None,
            open: Vec::new(),
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

    fn add_triangles(&mut self, triangles: &[PlacedTriangle]) -> std::io::Result<()> {
        for (t, [a, b, c]) in triangles {
            for i in t {
                self.faces.write_all(&i.to_le_bytes())?;
            }
            if let Some(volumes) = &mut self.volumes {
                volumes.write_all(&a.dot(b.cross(*c)).to_le_bytes())?;
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
        if let Some(volumes) = self.volumes.take() {
            let kept = kept_volumes(&mut self.sets, volumes, &mut faces, &mut count, least);
            let mut kept = kept.map_err(os)?;
            for &v in &self.open {
                let root = self.sets.find(u64::from(v)).map_err(os)?;
                report.pieces_open += u64::from(kept.remove(&root).is_some());
            }
            report.pieces_outward = outward(kept, &path)?;
        }
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

/// Six times the signed volume of each piece of at least `least`
/// triangles (`count` holds each root's triangles), by root: each face's
/// term (spooled in `volumes`) summed per piece of `sets`.
fn kept_volumes(
    sets: &mut ExternalSets,
    volumes: BufWriter<File>,
    faces: &mut BufReader<File>,
    count: &mut PagedU32,
    least: u32,
) -> std::io::Result<HashMap<u64, f64>> {
    let mut terms = rewind(volumes)?;
    faces.seek(SeekFrom::Start(0))?;
    let mut sums: HashMap<u64, f64> = HashMap::new();
    try_for_each_record::<12, std::io::Error>(faces, |r| {
        let mut term = [0u8; 8];
        terms.read_exact(&mut term)?;
        let a = u32::from_le_bytes([r[0], r[1], r[2], r[3]]);
        let root = sets.find(a as u64)?;
        if count.get(root)? >= least {
            *sums.entry(root).or_default() += f64::from_le_bytes(term);
        }
        Ok(())
    })?;
    Ok(sums)
}

/// How many kept pieces enclose a positive volume, or the error naming
/// those that do not (six times their volume in `sums`).
fn outward(sums: HashMap<u64, f64>, path: &std::path::Path) -> Result<u64, MeshError> {
    let pieces = sums.len() as u64;
    let inward: Vec<f64> = sums
        .into_values()
        .filter(|&v| v <= 0.0 || v.is_nan())
        .collect();
    if inward.is_empty() {
        return Ok(pieces);
    }
    Err(MeshError::InwardPieces {
        path: path.to_path_buf(),
        inward: inward.len() as u64,
        pieces,
        volume: inward.iter().copied().fold(f64::INFINITY, f64::min) / 6.0,
    })
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
    use crate::mesh::quality::quality;
    use crate::mesh::shapes::icosphere;
    use crate::mesh::{write_mesh, Mesh, MeshFormat};

    /// How the two spheres of [`write_two_spheres`] are written.
    #[derive(Clone, Copy)]
    struct Spheres {
        min_share: f64,
        /// Ask the filter to check volumes.
        outward: bool,
        /// Wind the small sphere inward.
        small_inward: bool,
    }

    fn placed(vertices: &[DVec3], tris: &[[u32; 3]], first: u32) -> Vec<PlacedTriangle> {
        let at = |i: u32| vertices[(i - first) as usize];
        tris.iter().map(|t| (*t, t.map(at))).collect()
    }

    /// A big sphere (1280 triangles), a small far one (20) written between its halves (so the
    /// kept vertices need renumbering), in batches as a stitcher would.
    fn write_two_spheres(path: &std::path::Path, min_share: f64) -> PieceReport {
        let how = Spheres {
            min_share,
            outward: false,
            small_inward: false,
        };
        write_spheres(path, how).unwrap()
    }

    fn write_spheres(path: &std::path::Path, how: Spheres) -> Result<PieceReport, MeshError> {
        let big = icosphere(3);
        let small = icosphere(0);
        let writer = MeshWriter::create(path, MeshFormat::PlyBinary).unwrap();
        let mut filter = PieceFilter::new(writer, how.min_share).unwrap();
        if how.outward {
            filter = filter.requiring_outward().unwrap();
        }
        let (half, rest) = big.triangles.split_at(big.triangles.len() / 2);
        filter.add_vertices(&big.vertices).unwrap();
        filter
            .add_triangles(&placed(&big.vertices, half, 0))
            .unwrap();
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
        filter
            .add_triangles(&placed(&far, &shifted, first))
            .unwrap();
        filter
            .add_triangles(&placed(&big.vertices, rest, 0))
            .unwrap();
        filter.finish().map(|f| f.2)
    }

    #[test]
    fn kept_pieces_wound_outward_pass_the_volume_check() {
        let dir = tempfile::tempdir().unwrap();
        let (checked, plain) = (dir.path().join("a.ply"), dir.path().join("b.ply"));
        for (share, kept) in [(0.0, 2), (0.05, 1)] {
            let how = Spheres {
                min_share: share,
                outward: true,
                small_inward: false,
            };
            let report = write_spheres(&checked, how).unwrap();
            assert_eq!(report.pieces_outward, kept, "share {share}");
            // The check changes nothing written.
            write_two_spheres(&plain, share);
            assert!(std::fs::read(&checked).unwrap() == std::fs::read(&plain).unwrap());
        }
    }

    #[test]
    fn an_inward_piece_fails_the_check_and_nothing_is_written() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.ply");
        let how = Spheres {
            min_share: 0.0,
            outward: true,
            small_inward: true,
        };
        match write_spheres(&path, how) {
            Err(MeshError::InwardPieces {
                inward: 1,
                pieces: 2,
                volume,
                ..
            }) => {
                // The small sphere's volume, 0.1^3 of an icosahedron's 2.54.
                assert!(volume < -0.002 && volume > -0.003, "{volume}");
            }
            other => panic!("{other:?}"),
        }
        assert!(!path.exists());
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
        // Named open (a boundary runs through vertex `first`), it is not
        // checked either.
        let writer = MeshWriter::create(&path, MeshFormat::PlyBinary).unwrap();
        let mut filter = PieceFilter::new(writer, 0.0)
            .unwrap()
            .requiring_outward()
            .unwrap();
        let small = icosphere(0);
        let first = filter.add_vertices(&small.vertices).unwrap();
        let inward: Vec<[u32; 3]> = small.triangles.iter().map(|&[a, b, c]| [a, c, b]).collect();
        filter
            .add_triangles(&placed(&small.vertices, &inward, first))
            .unwrap();
        filter.open_at(&[first + 3]);
        let report = filter.finish().unwrap().2;
        assert_eq!((report.pieces_outward, report.pieces_open), (0, 1));
        // Dropped as a small piece, it is not checked.
        let dropped = Spheres {
            min_share: 0.05,
            ..how
        };
        assert_eq!(write_spheres(&path, dropped).unwrap().pieces_outward, 1);
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
                pieces_outward: 0,
                pieces_open: 0,
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
