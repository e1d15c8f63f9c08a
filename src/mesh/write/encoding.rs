//! How each mesh format writes its parts, behind one trait: the header
//! (and where its counts are patched once they are known), a batch of
//! vertices, a batch of triangles, and how many vertices it can index.
//! A new mesh format is an [`Encoding`] here and a row in the output
//! table (`crate::io::mesh_format`); the streaming writer around it
//! (atomic file, face spool, audit, promise) is the same for all.

use super::{WriteOptions, COUNT_WIDTH};
use crate::io::MeshFormat;
use glam::DVec3;
use std::io::{Result, Write};

/// Where the two counts sit in a header that has them.
#[derive(Clone, Copy, Debug)]
pub struct CountOffsets {
    /// Byte offset of the vertex count.
    pub vertices: u64,
    /// Byte offset of the face count.
    pub faces: u64,
}

/// One mesh format's bytes. Batches, not single items: the format is
/// chosen once per batch, the loops inside stay monomorphic.
pub trait Encoding: Sync {
    /// Writes the header; returns where its counts sit, if it has any
    /// (fixed-width placeholders of [`COUNT_WIDTH`] digits).
    fn header(&self, w: &mut dyn Write, options: WriteOptions) -> Result<Option<CountOffsets>>;
    /// Writes `vertices`.
    fn vertices(&self, w: &mut dyn Write, vertices: &[DVec3], options: WriteOptions) -> Result<()>;
    /// Writes `triangles` (0-based indices; the limit is checked before).
    fn triangles(&self, w: &mut dyn Write, triangles: &[[u32; 3]]) -> Result<()>;
    /// Largest vertex count the format can index.
    fn vertex_limit(&self) -> u64;
}

/// The encoding of `format`.
pub fn encoding(format: MeshFormat) -> &'static dyn Encoding {
    match format {
        MeshFormat::PlyBinary => &Ply { ascii: false },
        MeshFormat::PlyAscii => &Ply { ascii: true },
        MeshFormat::Obj => &Obj,
    }
}

/// PLY: vertex `x, y, z` as `double` (or `float`), face `list uchar int
/// vertex_indices`, so at most 2^31 vertices.
struct Ply {
    ascii: bool,
}

impl Encoding for Ply {
    fn header(&self, w: &mut dyn Write, options: WriteOptions) -> Result<Option<CountOffsets>> {
        let kind = match self.ascii {
            true => "ascii",
            false => "binary_little_endian",
        };
        let scalar = match options.single_precision {
            true => "float",
            false => "double",
        };
        let placeholder = format!("{:0COUNT_WIDTH$}", 0);
        let mut header =
            format!("ply\nformat {kind} 1.0\ncomment written by scanmesh\nelement vertex ");
        let vertices = header.len() as u64;
        header.push_str(&placeholder);
        header.push_str(&format!(
            "\nproperty {scalar} x\nproperty {scalar} y\nproperty {scalar} z\nelement face "
        ));
        let faces = header.len() as u64;
        header.push_str(&placeholder);
        header.push_str("\nproperty list uchar int vertex_indices\nend_header\n");
        w.write_all(header.as_bytes())?;
        Ok(Some(CountOffsets { vertices, faces }))
    }

    fn vertices(&self, w: &mut dyn Write, vertices: &[DVec3], options: WriteOptions) -> Result<()> {
        let single = options.single_precision;
        match self.ascii {
            // Rust's float Display is the shortest text that reads back to
            // the same value, so ASCII output round-trips exactly.
            true if single => text_vertices(w, "", vertices.iter().map(|p| p.as_vec3().to_array())),
            true => text_vertices(w, "", vertices.iter().map(|p| p.to_array())),
            false if single => {
                let coords = vertices.iter().flat_map(|p| p.as_vec3().to_array());
                write_bytes(w, coords.map(f32::to_le_bytes))
            }
            false => {
                let coords = vertices.iter().flat_map(|p| p.to_array());
                write_bytes(w, coords.map(f64::to_le_bytes))
            }
        }
    }

    fn triangles(&self, w: &mut dyn Write, triangles: &[[u32; 3]]) -> Result<()> {
        if self.ascii {
            for t in triangles {
                writeln!(w, "3 {} {} {}", t[0], t[1], t[2])?;
            }
            return Ok(());
        }
        // Indices above i32::MAX are caught by the writer's `finish` (the
        // vertex limit), so the cast never writes a wrong index to a file
        // that gets committed.
        let face = |t: &[u32; 3]| {
            let mut b = [3u8; 13];
            for (k, i) in t.iter().enumerate() {
                b[1 + 4 * k..5 + 4 * k].copy_from_slice(&(*i as i32).to_le_bytes());
            }
            b
        };
        write_bytes(w, triangles.iter().map(face))
    }

    fn vertex_limit(&self) -> u64 {
        i32::MAX as u64 + 1
    }
}

/// Wavefront OBJ: `v x y z` lines and 1-based `f a b c` lines.
struct Obj;

impl Encoding for Obj {
    fn header(&self, w: &mut dyn Write, _: WriteOptions) -> Result<Option<CountOffsets>> {
        writeln!(w, "# written by scanmesh")?;
        Ok(None)
    }

    fn vertices(&self, w: &mut dyn Write, vertices: &[DVec3], options: WriteOptions) -> Result<()> {
        match options.single_precision {
            true => text_vertices(w, "v ", vertices.iter().map(|p| p.as_vec3().to_array())),
            false => text_vertices(w, "v ", vertices.iter().map(|p| p.to_array())),
        }
    }

    fn triangles(&self, w: &mut dyn Write, triangles: &[[u32; 3]]) -> Result<()> {
        for t in triangles {
            let [a, b, c] = t.map(|i| i as u64 + 1);
            writeln!(w, "f {a} {b} {c}")?;
        }
        Ok(())
    }

    fn vertex_limit(&self) -> u64 {
        u32::MAX as u64 + 1
    }
}

/// One line per vertex: `prefix` and its three coordinates.
fn text_vertices<T: std::fmt::Display>(
    w: &mut dyn Write,
    prefix: &str,
    vertices: impl Iterator<Item = [T; 3]>,
) -> Result<()> {
    for [x, y, z] in vertices {
        writeln!(w, "{prefix}{x} {y} {z}")?;
    }
    Ok(())
}

/// Bytes gathered before each write: a batch's size does not matter.
const CHUNK: usize = 1 << 16;

/// Writes `items` in chunks of at most [`CHUNK`] bytes.
fn write_bytes<const N: usize>(
    w: &mut dyn Write,
    items: impl Iterator<Item = [u8; N]>,
) -> Result<()> {
    let mut chunk = Vec::with_capacity(CHUNK);
    for item in items {
        if chunk.len() + N > CHUNK {
            w.write_all(&chunk)?;
            chunk.clear();
        }
        chunk.extend_from_slice(&item);
    }
    w.write_all(&chunk)
}
