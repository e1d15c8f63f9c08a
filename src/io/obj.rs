//! Wavefront OBJ mesh reading: `v` and `f` lines only (`f a`, `a/b`, `a/b/c`,
//! `a//c`; 1-based or negative, i.e. relative, indices). Polygons are
//! fan-triangulated; every other statement is ignored.

use super::source::{open_input, Input};
use super::text::{self, Line};
use super::IoError;
use glam::DVec3;
use std::path::Path;

/// Reads an OBJ mesh (gzip allowed): vertices and triangles.
pub fn read_obj_mesh(path: &Path) -> Result<(Vec<DVec3>, Vec<[u32; 3]>), IoError> {
    read_obj(path, open_input(path)?.input)
}

#[derive(Default)]
struct Obj {
    vertices: Vec<DVec3>,
    triangles: Vec<[u32; 3]>,
    poly: Vec<u32>,
    /// Largest forward index seen, with its line: checked at the end, since
    /// positive indices may name vertices defined later.
    max_index: Option<(u32, u64)>,
}

pub(crate) fn read_obj(
    path: &Path,
    mut input: Input,
) -> Result<(Vec<DVec3>, Vec<[u32; 3]>), IoError> {
    let mut obj = Obj::default();
    let mut line = Vec::new();
    let mut line_no = 0u64;
    loop {
        let got = text::read_line(&mut input, &mut line).map_err(|e| IoError::os(path, e))?;
        if got == Line::Eof {
            break;
        }
        line_no += 1;
        let bad = |record: usize, reason: String| IoError::BadRecord {
            path: path.to_path_buf(),
            record: record as u64,
            reason: format!("line {line_no}: {reason}"),
        };
        if got == Line::TooLong {
            return Err(bad(0, format!("longer than {} bytes", text::MAX_LINE)));
        }
        let s = text::as_text(&line).map_err(|e| bad(0, e))?;
        let mut tok = s.split_ascii_whitespace();
        match tok.next() {
            Some("v") => {
                let k = obj.vertices.len();
                let p = obj.vertex(tok).map_err(|e| bad(k, e))?;
                if let Some(value) = [p.x, p.y, p.z].into_iter().find(|c| !c.is_finite()) {
                    return Err(IoError::NonFinite {
                        path: path.to_path_buf(),
                        record: k as u64,
                        value,
                    });
                }
                obj.vertices.push(p);
            }
            Some("f") => {
                let k = obj.triangles.len();
                obj.face(tok, line_no).map_err(|e| bad(k, e))?;
            }
            _ => {}
        }
    }
    let n = obj.vertices.len();
    if let Some((i, at)) = obj.max_index.filter(|&(i, _)| i as usize >= n) {
        return Err(IoError::BadRecord {
            path: path.to_path_buf(),
            record: 0,
            reason: format!("line {at}: vertex {} does not exist ({n} vertices)", i + 1),
        });
    }
    Ok((obj.vertices, obj.triangles))
}

impl Obj {
    fn vertex<'a>(&self, mut tok: impl Iterator<Item = &'a str>) -> Result<DVec3, String> {
        let mut c = [0.0; 3];
        for (slot, name) in c.iter_mut().zip(["x", "y", "z"]) {
            let t = tok.next().ok_or("vertex with fewer than 3 coordinates")?;
            *slot = text::parse_f64(t, name)?;
        }
        Ok(DVec3::from_array(c))
    }

    fn face<'a>(&mut self, tok: impl Iterator<Item = &'a str>, line: u64) -> Result<(), String> {
        self.poly.clear();
        for t in tok {
            let i = self.index(t)?;
            if self.max_index.is_none_or(|(m, _)| i > m) {
                self.max_index = Some((i, line));
            }
            self.poly.push(i);
        }
        if self.poly.len() < 3 {
            return Err(format!("face with {} vertices (need 3)", self.poly.len()));
        }
        let a = self.poly[0];
        for w in self.poly[1..].windows(2) {
            self.triangles.push([a, w[0], w[1]]);
        }
        Ok(())
    }

    /// 0-based vertex index of a face corner `a`, `a/b`, `a/b/c` or `a//c`.
    fn index(&self, t: &str) -> Result<u32, String> {
        let first = t.split('/').next().unwrap_or("");
        let i: i64 = first
            .parse()
            .map_err(|_| format!("bad vertex index '{}'", text::shorten(t)))?;
        let zero_based = match i {
            0 => return Err("vertex index 0 (OBJ indices start at 1)".into()),
            i if i > 0 => i - 1,
            i => self.vertices.len() as i64 + i,
        };
        u32::try_from(zero_based).map_err(|_| format!("vertex index {i} out of range"))
    }
}
