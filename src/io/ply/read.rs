//! The streaming PLY point reader: elements before `vertex` are skipped,
//! vertex records are decoded in chunks, elements after it are never read.
//!
//! Binary vertices of fixed size take the block path ([`FixedLayout`]); ASCII
//! and list-carrying vertices the per-record path ([`RecordDecoder`]). Declared
//! counts are checked against the data (short data is
//! [`IoError::Truncated`]), never used to size allocations.
//!
//! Once the last vertex is read, the elements after `vertex` (faces) are
//! skipped and the file must end: data after the last declared element is
//! [`IoError::TrailingData`] (more vertices than the count, or garbage),
//! so a count too small never drops points silently. Blank lines may
//! follow an ASCII body and zero bytes a binary one (padding).

use super::attrs::AttrProps;
use super::binary::FixedLayout;
use super::header::{parse_header, Element, Encoding, PlyHeader};
use super::record::{rest, skip_element, RecordDecoder, RecordError, Rest};
use crate::io::policy::Admitter;
use crate::io::source::{read_full, Input};
use crate::io::{
    AttributeValues, Format, InvalidPolicy, IoError, PointChunk, PointReader, SourceInfo, Trailing,
};
use byteorder::{BigEndian, ByteOrder, LittleEndian};
use glam::{DVec3, Vec3};
use std::path::Path;

/// Raw bytes read per block on the binary path (bounded independently of
/// the caller's `max`, which bounds the decoded points).
const BLOCK_BYTES: usize = 1 << 20;

enum Body {
    Fixed {
        layout: FixedLayout,
        big_endian: bool,
        buf: Vec<u8>,
    },
    General {
        dec: RecordDecoder,
        xyz: [usize; 3],
        normals: Option<[usize; 3]>,
    },
}

pub struct PlyPointReader {
    info: SourceInfo,
    attrs: AttrProps,
    input: Input,
    admit: Admitter,
    body: Body,
    declared: u64,
    /// Vertex records consumed so far (kept or skipped).
    next: u64,
    /// The elements declared after `vertex`, skipped once it is read.
    after: Vec<Element>,
    encoding: Encoding,
    /// Whether the end of the file has been checked (after the last vertex).
    ended: bool,
}

impl PlyPointReader {
    /// Parses the header from `input` and positions it at the first vertex.
    pub(crate) fn open(
        path: &Path,
        mut input: Input,
        gzip: bool,
        policy: InvalidPolicy,
    ) -> Result<Self, IoError> {
        let bad = |reason: String| IoError::BadHeader {
            path: path.to_path_buf(),
            reason,
        };
        let header = parse_header(&mut input).map_err(bad)?;
        let v = header
            .element_index("vertex")
            .ok_or_else(|| bad("no 'vertex' element".into()))?;
        let vertex = &header.elements[v];
        let (xyz, normals) = vertex_props(vertex).map_err(bad)?;
        let attrs = AttrProps::find(vertex);
        let mut line_no = header.lines;
        for el in &header.elements[..v] {
            skip_element(&mut input, el, header.encoding, &mut line_no)
                .map_err(|(k, e)| element_error(path, el, k, e))?;
        }
        let body = make_body(&header, vertex, (xyz, normals), &attrs, line_no);
        let info = SourceInfo {
            path: path.to_path_buf(),
            format: format_of(header.encoding),
            gzip,
            declared_count: Some(vertex.count),
            has_normals: normals.is_some(),
            attributes: attrs.set(),
            header_bounds: None,
            las_transform: None,
        };
        Ok(PlyPointReader {
            admit: Admitter::new(path.to_path_buf(), policy),
            declared: vertex.count,
            next: 0,
            after: header.elements[v + 1..].to_vec(),
            encoding: header.encoding,
            ended: false,
            info,
            attrs,
            input,
            body,
        })
    }

    fn truncated(&self, found: u64) -> IoError {
        IoError::Truncated {
            path: self.info.path.clone(),
            declared: self.declared,
            found,
        }
    }

    fn read_block(&mut self, chunk: &mut PointChunk, want: u64) -> Result<(), IoError> {
        let Body::Fixed {
            layout,
            big_endian,
            buf,
        } = &mut self.body
        else {
            return Ok(());
        };
        let size = layout.size.max(1);
        let n = want.min((BLOCK_BYTES / size).max(1) as u64) as usize;
        buf.resize(n * size, 0);
        let got = read_full(&mut self.input, buf).map_err(|e| IoError::os(&self.info.path, e))?;
        let complete = got / size;
        let records = buf[..complete * size].chunks_exact(size);
        let first = self.next;
        let (admit, attrs) = (&mut self.admit, &self.attrs);
        let push = |k: usize, (p, nrm): (DVec3, Vec3), a: &AttributeValues| {
            admit.push_with(chunk, first + k as u64, p, nrm, a)
        };
        let decoded: Result<(), IoError> = match *big_endian {
            false => decode_all::<LittleEndian>(layout, attrs, records, push),
            true => decode_all::<BigEndian>(layout, attrs, records, push),
        };
        decoded?;
        self.next += complete as u64;
        if complete < n {
            return Err(self.truncated(self.next));
        }
        Ok(())
    }

    fn read_records(&mut self, chunk: &mut PointChunk, want: u64) -> Result<(), IoError> {
        let Body::General { dec, xyz, normals } = &mut self.body else {
            return Ok(());
        };
        for _ in 0..want {
            let record = self.next;
            match dec.read(&mut self.input) {
                Ok(()) => {}
                Err(RecordError::Eof) => {
                    return Err(IoError::Truncated {
                        path: self.info.path.clone(),
                        declared: self.declared,
                        found: record,
                    })
                }
                Err(RecordError::Cut { line }) => {
                    self.admit.cut(chunk, record, line)?;
                    self.next += 1;
                    continue;
                }
                Err(e) => return Err(record_error(&self.info.path, record, e)),
            }
            let v = &dec.values;
            let p = DVec3::new(v[xyz[0]], v[xyz[1]], v[xyz[2]]);
            let n = normals.map_or(Vec3::ZERO, |n| {
                Vec3::new(v[n[0]] as f32, v[n[1]] as f32, v[n[2]] as f32)
            });
            let a = self.attrs.values(|i| v[i]);
            self.admit.push_with(chunk, record, p, n, &a)?;
            self.next += 1;
        }
        Ok(())
    }

    /// After the last vertex: skips the elements declared after `vertex`,
    /// then checks that nothing but padding follows them.
    fn check_end(&mut self) -> Result<(), IoError> {
        self.ended = true;
        let path = &self.info.path;
        let (mut line_no, record) = match &self.body {
            Body::General { dec, .. } => (dec.line_no, None),
            Body::Fixed { layout, .. } => (0, Some(layout.size as u64)),
        };
        for el in &self.after {
            skip_element(&mut self.input, el, self.encoding, &mut line_no)
                .map_err(|(k, e)| element_error(path, el, k, e))?;
        }
        // Whole vertex records fit in the tail only when it follows them.
        let record = record.filter(|_| self.after.is_empty());
        let rest =
            rest(&mut self.input, self.encoding, line_no).map_err(|e| IoError::os(path, e))?;
        ensure_end(path, self.declared, rest, record)
    }
}

/// `Ok` when nothing (but padding) follows the declared elements, else
/// [`IoError::TrailingData`]; `record` is the vertex record size when the
/// vertices are the last element of a binary body.
pub(crate) fn ensure_end(
    path: &Path,
    declared: u64,
    rest: Rest,
    record: Option<u64>,
) -> Result<(), IoError> {
    let (extra_bytes, found) = match rest {
        Rest::End => return Ok(()),
        Rest::Line(line) => (
            None,
            Trailing::Line {
                line,
                declared: "elements",
            },
        ),
        Rest::Bytes(tail) => (Some(tail.bytes), tail.found(record)),
    };
    Err(IoError::TrailingData {
        path: path.to_path_buf(),
        declared,
        extra_bytes,
        found,
    })
}

impl PointReader for PlyPointReader {
    fn info(&self) -> &SourceInfo {
        &self.info
    }

    /// `max` of 0 is taken as 1, since 0 points read means end of input.
    fn read_chunk(&mut self, chunk: &mut PointChunk, max: usize) -> Result<usize, IoError> {
        let max = max.max(1);
        self.admit.begin(chunk, self.next, &self.info);
        while chunk.len() < max && self.next < self.declared {
            let want = ((max - chunk.len()) as u64).min(self.declared - self.next);
            match self.body {
                Body::Fixed { .. } => self.read_block(chunk, want)?,
                Body::General { .. } => self.read_records(chunk, want)?,
            }
        }
        // Checked in the call that reads the last vertex, so a caller that
        // stops at the declared count still gets the check.
        if self.next == self.declared && !self.ended {
            self.check_end()?;
        }
        Ok(self.admit.end(chunk))
    }

    fn skipped(&self) -> u64 {
        self.admit.skipped()
    }
}

fn decode_all<'a, B: ByteOrder>(
    layout: &FixedLayout,
    attrs: &AttrProps,
    records: impl Iterator<Item = &'a [u8]>,
    mut push: impl FnMut(usize, (DVec3, Vec3), &AttributeValues) -> Result<(), IoError>,
) -> Result<(), IoError> {
    let none = attrs.set().is_empty();
    for (k, rec) in records.enumerate() {
        let a = match none {
            true => AttributeValues::default(),
            false => attrs.values(|i| layout.prop::<B>(rec, i)),
        };
        push(k, layout.decode::<B>(rec), &a)?;
    }
    Ok(())
}

type PropIndices = ([usize; 3], Option<[usize; 3]>);

/// Property indices of x, y, z (required) and nx, ny, nz (all or nothing).
pub(crate) fn vertex_props(vertex: &Element) -> Result<PropIndices, String> {
    let need = |name: &str| {
        vertex
            .scalar(name)
            .map(|(i, _)| i)
            .ok_or_else(|| format!("vertex element has no scalar property '{name}'"))
    };
    let xyz = [need("x")?, need("y")?, need("z")?];
    let n = ["nx", "ny", "nz"].map(|name| vertex.scalar(name).map(|(i, _)| i));
    let normals = match n {
        [Some(a), Some(b), Some(c)] => Some([a, b, c]),
        _ => None,
    };
    Ok((xyz, normals))
}

fn make_body(
    header: &PlyHeader,
    vertex: &Element,
    (xyz, normals): PropIndices,
    attrs: &AttrProps,
    line_no: u64,
) -> Body {
    let fixed = match header.encoding {
        Encoding::Ascii => None,
        _ => FixedLayout::new(vertex, xyz, normals),
    };
    match fixed {
        Some(layout) => Body::Fixed {
            layout,
            big_endian: header.encoding == Encoding::BinaryBe,
            buf: Vec::new(),
        },
        None => {
            let mut wanted = xyz.to_vec();
            wanted.extend(normals.iter().flatten());
            wanted.extend(attrs.indices());
            let dec = RecordDecoder::new(vertex, header.encoding, &wanted, None, line_no);
            Body::General { dec, xyz, normals }
        }
    }
}

fn format_of(e: Encoding) -> Format {
    match e {
        Encoding::Ascii => Format::PlyAscii,
        Encoding::BinaryLe => Format::PlyBinaryLe,
        Encoding::BinaryBe => Format::PlyBinaryBe,
    }
}

pub(crate) fn record_error(path: &Path, record: u64, e: RecordError) -> IoError {
    match e {
        RecordError::Io(e) => IoError::os(path, e),
        RecordError::Bad(reason) => IoError::BadRecord {
            path: path.to_path_buf(),
            record,
            reason,
        },
        RecordError::Eof => IoError::BadRecord {
            path: path.to_path_buf(),
            record,
            reason: "file ends inside the record".into(),
        },
        RecordError::Cut { line } => IoError::CutShort {
            path: path.to_path_buf(),
            record,
            line,
        },
    }
}

/// An error while reading a non-vertex element (`found` records were whole).
pub(crate) fn element_error(path: &Path, el: &Element, found: u64, e: RecordError) -> IoError {
    match e {
        RecordError::Eof => IoError::BadRecord {
            path: path.to_path_buf(),
            record: found,
            reason: format!(
                "file ends inside element '{}': {} declared, {found} found",
                el.name, el.count
            ),
        },
        RecordError::Bad(reason) => IoError::BadRecord {
            path: path.to_path_buf(),
            record: found,
            reason: format!("element '{}': {reason}", el.name),
        },
        RecordError::Io(e) => IoError::os(path, e),
        RecordError::Cut { line } => IoError::CutShort {
            path: path.to_path_buf(),
            record: found,
            line,
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Three f32 vertices declared, `records` written, in either byte order,
    /// then `tail`.
    fn ply(big_endian: bool, records: u32, tail: &[u8]) -> Vec<u8> {
        let order = if big_endian { "big" } else { "little" };
        let mut b = format!(
            "ply\nformat binary_{order}_endian 1.0\nelement vertex 3\n\
             property float x\nproperty float y\nproperty float z\nend_header\n"
        )
        .into_bytes();
        for v in (0..records * 3).map(|i| i as f32 + 1.0) {
            b.extend(if big_endian {
                v.to_be_bytes()
            } else {
                v.to_le_bytes()
            });
        }
        b.extend_from_slice(tail);
        b
    }

    fn read(bytes: Vec<u8>, max: usize) -> Result<Vec<DVec3>, IoError> {
        let input: Input = Box::new(std::io::Cursor::new(bytes));
        let mut r = PlyPointReader::open(Path::new("t.ply"), input, false, InvalidPolicy::Reject)?;
        let mut chunk = PointChunk::default();
        let mut all = Vec::new();
        while r.read_chunk(&mut chunk, max)? > 0 {
            all.extend_from_slice(&chunk.xyz);
        }
        Ok(all)
    }

    #[test]
    fn records_past_the_declared_count_are_an_error_in_both_byte_orders() {
        for big_endian in [false, true] {
            for max in [1, 3, 10] {
                match read(ply(big_endian, 5, &[]), max) {
                    Err(
                        e @ IoError::TrailingData {
                            declared: 3,
                            extra_bytes: Some(24),
                            ..
                        },
                    ) => assert!(e.to_string().contains("t.ply"), "{e}"),
                    other => panic!("big endian {big_endian}, max {max}: {other:?}"),
                }
                assert_eq!(read(ply(big_endian, 3, &[]), max).unwrap().len(), 3);
                assert_eq!(read(ply(big_endian, 3, &[0; 40]), max).unwrap().len(), 3);
                assert!(read(ply(big_endian, 3, b"\n"), max).is_err());
            }
        }
    }
}
