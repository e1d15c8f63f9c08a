//! The streaming PLY point reader: elements before `vertex` are skipped,
//! vertex records are decoded in chunks, elements after it are never read.
//!
//! Binary vertices of fixed size take the block path ([`FixedLayout`]); ASCII
//! and list-carrying vertices the per-record path ([`RecordDecoder`]). Declared
//! counts are checked against the data (short data is
//! [`IoError::Truncated`]), never used to size allocations.
//!
//! Data after the last declared element is an error in ASCII (trailing
//! garbage, or a count that is too small) but is not looked for in binary
//! files, where writers are known to pad.

use super::attrs::AttrProps;
use super::binary::FixedLayout;
use super::header::{parse_header, Element, Encoding, PlyHeader};
use super::record::{skip_element, RecordDecoder, RecordError};
use crate::io::policy::Admitter;
use crate::io::source::{read_full, Input};
use crate::io::{
    AttributeValues, Format, InvalidPolicy, IoError, PointChunk, PointReader, SourceInfo,
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
    /// ASCII file whose last element is `vertex`: the rest must be blank.
    check_trailing: bool,
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
            check_trailing: header.encoding == Encoding::Ascii && v + 1 == header.elements.len(),
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

    /// After the last vertex of an ASCII file that ends with `vertex`, only
    /// blank lines may follow.
    fn check_rest(&mut self) -> Result<(), IoError> {
        self.check_trailing = false;
        let Body::General { dec, .. } = &mut self.body else {
            return Ok(());
        };
        match dec.next_line(&mut self.input) {
            Ok(false) => Ok(()),
            Ok(true) => Err(IoError::BadRecord {
                path: self.info.path.clone(),
                record: self.declared,
                reason: format!(
                    "line {}: data after the {} declared vertices (trailing garbage, or a wrong count)",
                    dec.line_no, self.declared
                ),
            }),
            Err(e) => Err(record_error(&self.info.path, self.declared, e)),
        }
    }
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
        if self.next == self.declared && self.check_trailing {
            self.check_rest()?;
        }
        Ok(self.admit.end(chunk))
    }

    fn skipped(&self) -> u64 {
        self.admit.skipped()
    }

    fn reopen(&self) -> Option<Result<Box<dyn PointReader>, IoError>> {
        if self.info.gzip || !matches!(self.body, Body::Fixed { .. }) {
            return None;
        }
        let (path, policy) = (&self.info.path, self.admit.policy());
        crate::io::source::reopen_with(path, |input, gzip| {
            PlyPointReader::open(path, input, gzip, policy)
        })
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
    }
}
