//! Whole-mesh PLY reading (vertices and faces), for ground-truth meshes and
//! `scanmesh eval`. Polygons are fan-triangulated; face indices are checked
//! against the vertex count. Elements other than `vertex` and `face` are
//! skipped; after the last element the file must end (blank lines or zero
//! bytes may follow), as for the point reader.

use super::header::{parse_header, Element, Encoding, PlyHeader, PropertyKind};
use super::read::{element_error, ensure_end, record_error, vertex_props};
use super::record::{rest, skip_element, RecordDecoder, RecordError};
use crate::io::source::{open_input, Input};
use crate::io::IoError;
use glam::DVec3;
use std::path::Path;

/// Vertices reserved up front at most, whatever the header declares.
const RESERVE_CAP: u64 = 1 << 20;

/// Reads a PLY mesh (ASCII or binary, gzip allowed): vertices and triangles.
/// A file without a `face` element gives an empty triangle list.
pub fn read_mesh(path: &Path) -> Result<(Vec<DVec3>, Vec<[u32; 3]>), IoError> {
    let opened = open_input(path)?;
    if !super::is_ply_magic(&opened.magic) {
        return Err(IoError::BadHeader {
            path: path.to_path_buf(),
            reason: "not a PLY file (does not start with 'ply')".into(),
        });
    }
    read_ply_mesh(path, opened.input)
}

pub(crate) fn read_ply_mesh(
    path: &Path,
    mut input: Input,
) -> Result<(Vec<DVec3>, Vec<[u32; 3]>), IoError> {
    let bad = |reason: String| IoError::BadHeader {
        path: path.to_path_buf(),
        reason,
    };
    let header = parse_header(&mut input).map_err(bad)?;
    let v = header
        .element_index("vertex")
        .ok_or_else(|| bad("no 'vertex' element".into()))?;
    let f = header.element_index("face");
    let face_list = match f {
        Some(f) => Some(face_list_index(&header.elements[f]).map_err(bad)?),
        None => None,
    };
    let mut reader = MeshReader {
        path,
        header: &header,
        line_no: header.lines,
        vertices: Vec::new(),
        triangles: Vec::new(),
    };
    for (i, el) in header.elements.iter().enumerate() {
        if i == v {
            reader.read_vertices(&mut input, el)?;
        } else if Some(i) == f {
            reader.read_faces(&mut input, el, face_list.unwrap_or(0), v < i)?;
        } else {
            skip_element(&mut input, el, header.encoding, &mut reader.line_no)
                .map_err(|(k, e)| element_error(path, el, k, e))?;
        }
    }
    if f.is_some_and(|f| f < v) {
        reader.check_all_indices()?;
    }
    let rest =
        rest(&mut input, header.encoding, reader.line_no).map_err(|e| IoError::os(path, e))?;
    let vertex = &header.elements[v];
    let last = v + 1 == header.elements.len() && header.encoding != Encoding::Ascii;
    let record = vertex.fixed_size().filter(|_| last).map(|s| s as u64);
    ensure_end(path, vertex.count, rest, record)?;
    Ok((reader.vertices, reader.triangles))
}

/// The face list: `vertex_indices` or `vertex_index`, else the only list.
fn face_list_index(face: &Element) -> Result<usize, String> {
    let is_list = |i: &usize| matches!(face.props[*i].kind, PropertyKind::List { .. });
    let lists: Vec<usize> = (0..face.props.len()).filter(is_list).collect();
    let named = lists.iter().copied().find(|&i| {
        matches!(
            face.props[i].name.as_str(),
            "vertex_indices" | "vertex_index"
        )
    });
    match (named, lists.as_slice()) {
        (Some(i), _) => Ok(i),
        (None, [only]) => Ok(*only),
        _ => Err("face element has no 'vertex_indices' list".into()),
    }
}

struct MeshReader<'a> {
    path: &'a Path,
    header: &'a PlyHeader,
    line_no: u64,
    vertices: Vec<DVec3>,
    triangles: Vec<[u32; 3]>,
}

impl MeshReader<'_> {
    fn decoder(&self, el: &Element, wanted: &[usize], keep: Option<usize>) -> RecordDecoder {
        RecordDecoder::new(el, self.header.encoding, wanted, keep, self.line_no)
    }

    fn fail(&self, el: &Element, k: u64, e: RecordError) -> IoError {
        match e {
            RecordError::Eof => element_error(self.path, el, k, e),
            e => record_error(self.path, k, e),
        }
    }

    fn read_vertices(&mut self, input: &mut Input, el: &Element) -> Result<(), IoError> {
        let (xyz, _) = vertex_props(el).map_err(|reason| IoError::BadHeader {
            path: self.path.to_path_buf(),
            reason,
        })?;
        let mut dec = self.decoder(el, &xyz, None);
        self.vertices.reserve(el.count.min(RESERVE_CAP) as usize);
        for k in 0..el.count {
            dec.read(input).map_err(|e| self.fail(el, k, e))?;
            let p = DVec3::new(dec.values[xyz[0]], dec.values[xyz[1]], dec.values[xyz[2]]);
            if let Some(value) = [p.x, p.y, p.z].into_iter().find(|c| !c.is_finite()) {
                return Err(IoError::NonFinite {
                    path: self.path.to_path_buf(),
                    record: k,
                    value,
                });
            }
            self.vertices.push(p);
        }
        self.line_no = dec.line_no;
        Ok(())
    }

    /// Fan-triangulates each polygon; indices are checked now when the
    /// vertices are already known (`vertices_read`), else afterwards.
    fn read_faces(
        &mut self,
        input: &mut Input,
        el: &Element,
        list: usize,
        vertices_read: bool,
    ) -> Result<(), IoError> {
        let mut dec = self.decoder(el, &[], Some(list));
        let limit = if vertices_read {
            self.vertices.len() as u64
        } else {
            u64::from(u32::MAX) + 1
        };
        for k in 0..el.count {
            dec.read(input).map_err(|e| self.fail(el, k, e))?;
            let bad = |reason: String| IoError::BadRecord {
                path: self.path.to_path_buf(),
                record: k,
                reason: format!("face: {reason}"),
            };
            let poly = &dec.list;
            if poly.len() < 3 {
                return Err(bad(format!("{} vertices (need at least 3)", poly.len())));
            }
            let idx = |v: f64| -> Result<u32, IoError> {
                match v >= 0.0 && v.fract() == 0.0 && v < limit as f64 {
                    true => Ok(v as u32),
                    false => Err(bad(format!("vertex index {v} out of range 0..{limit}"))),
                }
            };
            let a = idx(poly[0])?;
            for w in poly[1..].windows(2) {
                self.triangles.push([a, idx(w[0])?, idx(w[1])?]);
            }
        }
        self.line_no = dec.line_no;
        Ok(())
    }

    /// For files whose faces precede their vertices.
    fn check_all_indices(&self) -> Result<(), IoError> {
        let n = self.vertices.len() as u64;
        for (t, tri) in self.triangles.iter().enumerate() {
            if let Some(&i) = tri.iter().find(|&&i| u64::from(i) >= n) {
                return Err(IoError::BadRecord {
                    path: self.path.to_path_buf(),
                    record: t as u64,
                    reason: format!("triangle {t}: vertex index {i} out of range 0..{n}"),
                });
            }
        }
        Ok(())
    }
}
