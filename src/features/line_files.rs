//! The feature-line graph's files, each format behind one trait
//! ([`LineEncoding`]): PLY with `element vertex` (x, y, z double) and
//! `element edge` (vertex1, vertex2 int, kind uchar: 1 ridge, 2 valley),
//! binary or ASCII, or OBJ with `l` records grouped `ridge` and `valley`.
//! A new line format is an encoding here and a row in the output table
//! (`crate::io::mesh_format`), which every command writing lines asks.

use super::lines::LineGraph;
use crate::geom::LineKind;
use crate::io::{AtomicFile, IoError, MeshFormat};
use glam::DVec3;
use std::io::{BufWriter, Write};
use std::path::Path;

/// One line format's bytes for a whole graph, vertices offset by `origin`.
pub trait LineEncoding: Sync {
    /// Writes `graph` to `out`.
    fn write(&self, graph: &LineGraph, origin: DVec3, out: &mut dyn Write) -> std::io::Result<()>;
}

/// The encoding of `format`.
pub fn line_encoding(format: MeshFormat) -> &'static dyn LineEncoding {
    match format {
        MeshFormat::PlyBinary => &PlyLines { ascii: false },
        MeshFormat::PlyAscii => &PlyLines { ascii: true },
        MeshFormat::Obj => &ObjLines,
    }
}

impl LineGraph {
    /// Writes `format` (the output table's [`crate::io::mesh_format`] for
    /// the path), vertices offset by `origin`; the file appears under its
    /// name only once whole.
    pub fn write(&self, path: &Path, origin: DVec3, format: MeshFormat) -> Result<(), IoError> {
        let mut file = AtomicFile::create(path)?;
        {
            let mut out = BufWriter::with_capacity(1 << 20, file.file());
            let os = |e| IoError::os(path, e);
            line_encoding(format)
                .write(self, origin, &mut out)
                .map_err(os)?;
            out.flush().map_err(os)?;
        }
        file.commit()
    }
}

/// PLY, binary little-endian or ASCII.
struct PlyLines {
    ascii: bool,
}

impl LineEncoding for PlyLines {
    fn write(&self, graph: &LineGraph, origin: DVec3, out: &mut dyn Write) -> std::io::Result<()> {
        let format = match self.ascii {
            true => "ascii",
            false => "binary_little_endian",
        };
        write!(
            out,
            "ply\nformat {format} 1.0\ncomment scanmesh features (paper 5): edge kind 1 ridge, 2 valley\n\
             element vertex {}\nproperty double x\nproperty double y\nproperty double z\n\
             element edge {}\nproperty int vertex1\nproperty int vertex2\nproperty uchar kind\nend_header\n",
            graph.vertices.len(),
            graph.edges.len()
        )?;
        for v in &graph.vertices {
            let p = *v + origin;
            if self.ascii {
                writeln!(out, "{} {} {}", p.x, p.y, p.z)?;
            } else {
                for c in p.to_array() {
                    out.write_all(&c.to_le_bytes())?;
                }
            }
        }
        for &(a, b, k) in &graph.edges {
            if self.ascii {
                writeln!(out, "{a} {b} {}", k as u8)?;
            } else {
                out.write_all(&(a as i32).to_le_bytes())?;
                out.write_all(&(b as i32).to_le_bytes())?;
                out.write_all(&[k as u8])?;
            }
        }
        Ok(())
    }
}

/// Wavefront OBJ: `v` records, then `l` records grouped by kind.
struct ObjLines;

impl LineEncoding for ObjLines {
    fn write(&self, graph: &LineGraph, origin: DVec3, out: &mut dyn Write) -> std::io::Result<()> {
        writeln!(
            out,
            "# scanmesh features (paper 5): groups ridge and valley"
        )?;
        for v in &graph.vertices {
            let p = *v + origin;
            writeln!(out, "v {} {} {}", p.x, p.y, p.z)?;
        }
        for (kind, name) in [(LineKind::Ridge, "ridge"), (LineKind::Valley, "valley")] {
            writeln!(out, "g {name}")?;
            for &(a, b, _) in graph.edges.iter().filter(|e| e.2 == kind) {
                writeln!(out, "l {} {}", a + 1, b + 1)?;
            }
        }
        Ok(())
    }
}
