//! Choosing a reader for a file: by content first (gzip, `ply`, `LASF`
//! magic), by name only for text formats, which have no magic; reading a
//! whole mesh, or a reader's points whole.

use super::e57::{is_e57_magic, E57Reader};
use super::las::LasReader;
use super::obj::read_obj;
use super::pcd::{is_pcd_magic, PcdReader};
use super::ply::{is_ply_magic, read_ply_mesh, PlyPointReader};
use super::select;
use super::source::{open_input, open_stream, Opened};
use super::xyz::XyzReader;
use super::{
    format_from_name, Format, InvalidPolicy, IoError, PointChunk, PointReader, ReadOptions,
};
use glam::DVec3;
use std::path::Path;

const LAS_MAGIC: &[u8] = b"LASF";

/// Opens a point file of any supported format for streaming.
///
/// gzip (`1f 8b`) is decompressed transparently and the inner content
/// sniffed; `ply\n` means PLY, `LASF` LAS/LAZ, a PCD header line PCD,
/// `ASTM-E57` E57; anything else is read as
/// XYZ/CSV text if its name says so (`.xyz`, `.txt`, `.csv`, `.pts`, each
/// optionally `.gz`), else it is [`IoError::UnknownFormat`].
///
/// `read` is an [`InvalidPolicy`] or [`ReadOptions`];
/// a scan selection is refused for a format without scans.
pub fn open_reader(
    path: &Path,
    read: impl Into<ReadOptions>,
) -> Result<Box<dyn PointReader>, IoError> {
    let read: ReadOptions = read.into();
    let opened = open_input(path)?;
    if is_e57_magic(&opened.magic) && !opened.gzip {
        // The e57 crate wants a seekable file: reopen it plainly.
        drop(opened);
        let e57 = Box::new(E57Reader::open(path, &read)?);
        return select::Selecting::wrap(e57, &read.select);
    }
    if read.scans.is_some() {
        return Err(IoError::Unsupported {
            path: path.to_path_buf(),
            reason: "a scan selection applies to E57 files only; this file is not one".into(),
        });
    }
    if is_e57_magic(&opened.magic) {
        return Err(IoError::Unsupported {
            path: path.to_path_buf(),
            reason: "gzip-compressed E57 cannot be read as a stream; gunzip it".into(),
        });
    }
    if opened.magic.starts_with(LAS_MAGIC) && !opened.gzip {
        // The las crate wants a seekable file: reopen it plainly.
        drop(opened);
        let las = Box::new(LasReader::open(path, read.policy)?);
        return select::Selecting::wrap(las, &read.select);
    }
    let r = streamed_format(path, opened, read.policy)?;
    select::Selecting::wrap(r, &read.select)
}

/// Opens points from any byte stream (an embedded sample, a network
/// body, a pipe) in the formats that read front to back: PLY, PCD and
/// XYZ/CSV text, gzip allowed. `name` names the stream in errors and, for
/// text, says its format (`.xyz`, `.csv`, ...). LAS/LAZ and E57 need a
/// seekable file and are refused with a reason.
pub fn open_stream_reader(
    name: &Path,
    stream: impl std::io::Read + Send + 'static,
    read: impl Into<ReadOptions>,
) -> Result<Box<dyn PointReader>, IoError> {
    let read: ReadOptions = read.into();
    let opened = open_stream(name, stream)?;
    if is_e57_magic(&opened.magic) || opened.magic.starts_with(LAS_MAGIC) {
        return Err(IoError::Unsupported {
            path: name.to_path_buf(),
            reason: "LAS, LAZ and E57 need a seekable file: save the stream and open the path"
                .into(),
        });
    }
    if read.scans.is_some() {
        return Err(IoError::Unsupported {
            path: name.to_path_buf(),
            reason: "a scan selection applies to E57 files only; this stream is not one".into(),
        });
    }
    let inner = streamed_format(name, opened, read.policy)?;
    let inner = select::Selecting::wrap(inner, &read.select)?;
    Ok(Box::new(Streamed(inner)))
}

/// A reader over a stream that cannot be read again.
struct Streamed(Box<dyn PointReader>);

impl PointReader for Streamed {
    fn info(&self) -> &super::SourceInfo {
        self.0.info()
    }
    fn read_chunk(&mut self, chunk: &mut super::PointChunk, max: usize) -> Result<usize, IoError> {
        self.0.read_chunk(chunk, max)
    }
    fn skipped(&self) -> u64 {
        self.0.skipped()
    }
    fn left_out(&self) -> super::LeftOut {
        self.0.left_out()
    }
    fn stations(&self) -> Vec<super::ScanStation> {
        self.0.stations()
    }
}

/// The reader for a front-to-back format, by content (PLY, PCD) or, for
/// text, by name.
fn streamed_format(
    path: &Path,
    opened: Opened,
    policy: InvalidPolicy,
) -> Result<Box<dyn PointReader>, IoError> {
    if is_ply_magic(&opened.magic) {
        let r = PlyPointReader::open(path, opened.input, opened.gzip, policy)?;
        return Ok(Box::new(r));
    }
    if is_pcd_magic(&opened.magic) {
        let r = PcdReader::open(path, opened.input, opened.gzip, policy)?;
        return Ok(Box::new(r));
    }
    if opened.magic.starts_with(LAS_MAGIC) {
        return Err(IoError::Unsupported {
            path: path.to_path_buf(),
            reason: "gzip-compressed LAS cannot be read as a stream; gunzip it or use LAZ".into(),
        });
    }
    let bad = |magic: &str| IoError::BadHeader {
        path: path.to_path_buf(),
        reason: format!("named as this format, but does not start with '{magic}'"),
    };
    match format_from_name(path) {
        Some((Format::Xyz, _)) => Ok(Box::new(XyzReader::open(
            path,
            opened.input,
            opened.gzip,
            policy,
        )?)),
        Some((Format::Las | Format::Laz, _)) => Err(bad("LASF")),
        Some((Format::Pcd, _)) => Err(bad("# .PCD, VERSION or FIELDS")),
        Some((Format::E57, _)) => Err(bad("ASTM-E57")),
        Some(_) => Err(bad("ply")),
        None => Err(IoError::UnknownFormat {
            path: path.to_path_buf(),
        }),
    }
}

/// Every point `reader` has left, its coordinates only, read in chunks (a
/// picture's points, a distance reference: inputs held whole by design).
pub fn read_all_xyz(reader: &mut dyn PointReader) -> Result<Vec<DVec3>, IoError> {
    let mut chunk = PointChunk::default();
    let mut points = Vec::new();
    while reader.read_chunk(&mut chunk, 1 << 16)? > 0 {
        points.extend_from_slice(&chunk.xyz);
    }
    Ok(points)
}

/// Reads a whole triangle mesh: PLY (by its magic, gzip allowed) or OBJ (by a
/// `.obj` / `.obj.gz` name). Polygons are fan-triangulated.
pub fn read_mesh_any(path: &Path) -> Result<(Vec<DVec3>, Vec<[u32; 3]>), IoError> {
    let file = std::fs::File::open(path).map_err(|e| IoError::os(path, e))?;
    read_mesh_from(path, file)
}

/// Like [`read_mesh_any`] over any byte stream; `name` names it in errors
/// and, for OBJ, says its format.
pub fn read_mesh_from(
    name: &Path,
    stream: impl std::io::Read + Send + 'static,
) -> Result<(Vec<DVec3>, Vec<[u32; 3]>), IoError> {
    let path = name;
    let opened = open_stream(path, stream)?;
    if is_ply_magic(&opened.magic) {
        return read_ply_mesh(path, opened.input);
    }
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    if name.ends_with(".obj") || name.ends_with(".obj.gz") {
        return read_obj(path, opened.input);
    }
    Err(IoError::Unsupported {
        path: path.to_path_buf(),
        reason: "unknown mesh format (expected PLY content, or an .obj / .obj.gz name)".into(),
    })
}
