//! Streaming mesh output: PLY (binary little-endian or ASCII) and OBJ, in
//! memory that does not grow with the mesh (ARCHITECTURE.md, "Writers").
//!
//! Vertices stream into the final file (an [`AtomicFile`], under a
//! temporary name) right after a header whose counts are fixed-width
//! placeholders; faces stream into an unnamed scratch file in the same
//! directory (the OS removes it on drop or on a crash). `finish` appends the
//! faces, patches the counts in place (same width, so nothing shifts) and
//! renames the file into place. Dropping an unfinished writer leaves nothing.
//!
//! Every mesh written is audited on the way ([`super::audit`]): `finish`
//! returns the counts with the file, and a writer that was given a
//! [`Promise`] the mesh breaks renames its file to `NAME.incomplete.EXT`
//! instead ([`incomplete_path`]) and fails, naming what broke it.
//!
//! Each format's bytes are its [`Encoding`] (`encoding`): binary PLY
//! writes vertex `x, y, z` as `double` (or `float` with
//! [`WriteOptions::single_precision`]), face `list uchar int
//! vertex_indices` (so at most 2^31 vertices). Counts are written as 20
//! zero-padded digits, which every PLY reader parses as the plain decimal
//! number.

mod encoding;

pub use encoding::Encoding;

use super::audit::{incomplete_path, Auditor, MeshAudit, Promise, Sizes};
use super::error::non_finite_coordinate;
use super::scratch::scratch_beside;
use super::{Mesh, MeshError};
use crate::io::{AtomicFile, IoError};
use encoding::CountOffsets;
use glam::DVec3;
use std::fs::File;
use std::io::{BufWriter, Seek, SeekFrom, Write};
use std::path::Path;

pub use crate::io::MeshFormat;

/// Options of a mesh output.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct WriteOptions {
    /// Write vertex coordinates as 32-bit floats instead of doubles.
    pub single_precision: bool,
}

/// Width of the patched count fields in a PLY header.
pub(crate) const COUNT_WIDTH: usize = 20;
/// Buffer per stream: large writes, flat memory.
const BUFFER: usize = 1 << 20;

/// A streaming mesh writer: vertices go to the output as they come, triangles to a scratch file appended on finish; the file appears under its name only then.
pub struct MeshWriter {
    // Sinks first: they drop (and flush into the doomed temporary) before
    // `out` removes it.
    vertex_sink: BufWriter<File>,
    face_sink: BufWriter<File>,
    out: AtomicFile,
    encoding: &'static dyn Encoding,
    options: WriteOptions,
    counts_at: Option<CountOffsets>,
    vertices: u64,
    triangles: u64,
    /// Largest index seen so far and the first triangle that used it.
    max_index: Option<(u32, u64)>,
    audit: Auditor,
    promise: Promise,
}

/// What [`MeshWriter::finish`] wrote: the counts and the audit of the mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Written {
    /// Vertices written.
    pub vertices: u64,
    /// Triangles written.
    pub triangles: u64,
    /// What the mesh is: its edges, vertices, components and volumes.
    pub audit: MeshAudit,
}

impl Written {
    /// The vertex and triangle counts.
    pub fn counts(&self) -> (u64, u64) {
        (self.vertices, self.triangles)
    }
}

impl MeshWriter {
    /// A writer of `path` in `format`, coordinates as doubles.
    pub fn create(path: &Path, format: MeshFormat) -> Result<Self, MeshError> {
        Self::create_with(path, format, WriteOptions::default())
    }

    /// A writer of `path` in `format` with `options`.
    pub fn create_with(
        path: &Path,
        format: MeshFormat,
        options: WriteOptions,
    ) -> Result<Self, MeshError> {
        let mut out = AtomicFile::create(path)?;
        let os = |e| MeshError::Io(IoError::os(path, e));
        let scratch = scratch_beside(path).map_err(os)?;
        let mut vertex_sink = BufWriter::with_capacity(BUFFER, out.file().try_clone().map_err(os)?);
        let encoding = encoding::encoding(format);
        let counts_at = encoding.header(&mut vertex_sink, options).map_err(os)?;
        let audit = Auditor::new(path, Sizes::DEFAULT).map_err(os)?;
        Ok(MeshWriter {
            vertex_sink,
            face_sink: BufWriter::with_capacity(BUFFER, scratch),
            out,
            encoding,
            options,
            counts_at,
            vertices: 0,
            triangles: 0,
            max_index: None,
            audit,
            promise: Promise::NOTHING,
        })
    }

    /// The writer, checking `promise` at the end: a mesh that breaks it
    /// is written as `NAME.incomplete.EXT` and `finish` fails with
    /// [`MeshError::PromiseBroken`].
    pub fn promising(self, promise: Promise) -> Self {
        MeshWriter { promise, ..self }
    }

    /// The final path of the output.
    pub fn path(&self) -> &Path {
        self.out.final_path()
    }

    /// Appends vertices; returns the global index of the first one. The
    /// batch is checked before anything is written, so a refused batch
    /// leaves the writer as it was.
    pub fn add_vertices(&mut self, vertices: &[DVec3]) -> Result<u32, MeshError> {
        let first = self.vertices;
        let count = first + vertices.len() as u64;
        let limit = self.encoding.vertex_limit();
        let too_many = || MeshError::TooManyVertices {
            path: self.path().to_path_buf(),
            count,
            limit,
        };
        if count > limit {
            return Err(too_many());
        }
        // An empty batch on a full writer has no index to return.
        let first_index = u32::try_from(first).map_err(|_| too_many())?;
        if let Some((i, value)) = vertices
            .iter()
            .enumerate()
            .find_map(|(i, &p)| non_finite_coordinate(p).map(|v| (i, v)))
        {
            return Err(MeshError::NonFiniteOutput {
                path: self.path().to_path_buf(),
                vertex: first + i as u64,
                value,
            });
        }
        let written = self
            .encoding
            .vertices(&mut self.vertex_sink, vertices, self.options);
        written.map_err(|e| self.os(e))?;
        let audited = self.audit.add_vertices(vertices);
        audited.map_err(|e| self.os(e))?;
        self.vertices = count;
        Ok(first_index)
    }

    /// Appends triangles by global vertex index. Indices may refer to
    /// vertices not yet added; `finish` checks them all. After an I/O error
    /// the writer is unusable: drop it (which removes the partial output).
    pub fn add_triangles(&mut self, triangles: &[[u32; 3]]) -> Result<(), MeshError> {
        for (k, t) in triangles.iter().enumerate() {
            let m = t[0].max(t[1]).max(t[2]);
            if self.max_index.is_none_or(|(best, _)| m > best) {
                self.max_index = Some((m, self.triangles + k as u64));
            }
        }
        let written = self.encoding.triangles(&mut self.face_sink, triangles);
        written.map_err(|e| self.os(e))?;
        self.triangles += triangles.len() as u64;
        let audited = self.audit.add_triangles(triangles);
        audited.map_err(|e| self.os(e))
    }

    /// Completes the file, audits the mesh and renames the file into
    /// place; returns the counts written and the audit. When the mesh
    /// breaks the writer's [`Promise`], the file goes to
    /// [`incomplete_path`] instead and the error names what broke it.
    pub fn finish(mut self) -> Result<Written, MeshError> {
        if let Some((index, triangle)) = self.max_index.filter(|&(m, _)| m as u64 >= self.vertices)
        {
            return Err(MeshError::DanglingIndex {
                path: self.path().to_path_buf(),
                triangle,
                index,
                vertex_count: self.vertices,
            });
        }
        self.assemble().map_err(|e| self.os(e))?;
        let MeshWriter {
            out,
            audit,
            promise,
            vertices,
            triangles,
            ..
        } = self;
        let path = out.final_path().to_path_buf();
        let audit = audit
            .finish()
            .map_err(|e| MeshError::Io(IoError::os(&path, e)))?;
        let failures = promise.broken_by(&audit);
        if failures.is_empty() {
            out.commit()?;
            return Ok(Written {
                vertices,
                triangles,
                audit,
            });
        }
        let written = incomplete_path(&path);
        out.commit_to(&written)?;
        Err(MeshError::PromiseBroken {
            path,
            written,
            promise,
            failures,
            audit: Box::new(audit),
        })
    }

    /// Appends the faces to the vertices and patches the header counts.
    fn assemble(&mut self) -> std::io::Result<()> {
        self.vertex_sink.flush()?;
        self.face_sink.flush()?;
        let file = self.vertex_sink.get_mut();
        let scratch = self.face_sink.get_mut();
        scratch.seek(SeekFrom::Start(0))?;
        file.seek(SeekFrom::End(0))?;
        std::io::copy(scratch, file)?;
        if let Some(at) = self.counts_at {
            for (offset, count) in [(at.vertices, self.vertices), (at.faces, self.triangles)] {
                file.seek(SeekFrom::Start(offset))?;
                write!(file, "{count:0COUNT_WIDTH$}")?;
            }
        }
        Ok(())
    }

    fn os(&self, e: std::io::Error) -> MeshError {
        MeshError::Io(IoError::os(self.path(), e))
    }
}

/// Writes `mesh` to `path` in one go (streamed in batches through
/// [`MeshWriter`]); returns the counts and the audit.
pub fn write_mesh(path: &Path, mesh: &Mesh, format: MeshFormat) -> Result<Written, MeshError> {
    const BATCH: usize = 1 << 16;
    let mut writer = MeshWriter::create(path, format)?;
    for chunk in mesh.vertices.chunks(BATCH) {
        writer.add_vertices(chunk)?;
    }
    for chunk in mesh.triangles.chunks(BATCH) {
        writer.add_triangles(chunk)?;
    }
    writer.finish()
}
