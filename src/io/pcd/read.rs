//! The streaming PCD point reader: `x y z` (and `normal_x normal_y
//! normal_z` when present) out of ASCII lines, binary records, or the
//! columns of a `binary_compressed` body; with the attributes PCL's point
//! types carry (`intensity`; `rgb` or `rgba` packed 0x(AA)RRGGBB, 8 bits a
//! channel, widened to 16) and those scanmesh writes (`classification`,
//! `return_number`, `gps_time`).
//!
//! A compressed body is one LZF block of whole columns (all x, then all y,
//! ...), so no point can be decoded before the block ends. It is
//! decompressed, streaming, into an unnamed temporary file (removed by the
//! system when the reader is dropped, even on a kill) and the columns are
//! read from there side by side: memory stays a chunk's worth whatever the
//! cloud's size, disk is the uncompressed size. PCD's `VIEWPOINT` is not
//! applied to the points, as PCL does not apply it when loading.
//!
//! Field names are matched whatever their case (PDAL writes `X Y Z`). An
//! organised cloud (`HEIGHT` > 1, a sensor's pixel grid) marks a pixel
//! without a return with NaN coordinates: such records are left out and
//! counted ([`LeftOut::no_return`]) under every policy, while NaN in an
//! unorganised cloud stays an invalid record (an error unless skipped).
//!
//! After the declared points the file must end: blank lines may follow an
//! ASCII body and zero bytes a binary one (PCL pads its binary and
//! binary_compressed files with zeros), anything else is
//! [`IoError::TrailingData`]. An ASCII body's last line must end with an
//! end of line (else it may be cut inside its last number).

use super::header::{parse_header, Data, PcdHeader, Scalar};
use super::lzf;
use crate::io::attributes::{to_unsigned, widen_8bit};
use crate::io::policy::Admitter;
use crate::io::source::{binary_tail, read_full, Input, Tail};
use crate::io::text::{self, Line};
use crate::io::{
    Attribute, AttributeSet, AttributeValues, Format, InvalidPolicy, IoError, LeftOut, PointChunk,
    PointReader, SourceInfo, Trailing,
};
use byteorder::{ByteOrder, LittleEndian};
use glam::{DVec3, Vec3};
use std::fs::File;
use std::io::{BufRead, Read};
use std::os::unix::fs::FileExt;
use std::path::Path;

/// Raw bytes read per binary block.
const BLOCK_BYTES: usize = 1 << 20;

/// Where the fields of interest sit, as field indices into the header:
/// `[x, y, z, nx, ny, nz]`, then the attributes of [`ATTRIBUTE_FIELDS`].
type Wanted = [Option<usize>; SLOTS];

/// The decoded values of one record, by slot of [`Wanted`]; the packed
/// colour as its 32 bits.
type Values = [f64; SLOTS];

const SLOTS: usize = 11;
const RGB_SLOT: usize = 7;

enum Body {
    Ascii { line: Vec<u8>, line_no: u64 },
    Binary { buf: Vec<u8> },
    Columns { file: File, buf: Vec<u8> },
}

pub struct PcdReader {
    info: SourceInfo,
    input: Input,
    admit: Admitter,
    header: PcdHeader,
    wanted: Wanted,
    body: Body,
    /// Records consumed so far (kept or skipped).
    next: u64,
    /// Whether the end of the file has been checked (after the last record).
    ended: bool,
    /// Whether the cloud is organised (`HEIGHT` > 1): NaN coordinates are
    /// then a pixel without a return, left out under every policy.
    organised: bool,
}

impl PcdReader {
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
        let wanted = wanted_fields(&header).map_err(bad)?;
        let body = match header.data {
            Data::Ascii => Body::Ascii {
                line: Vec::new(),
                line_no: header.lines,
            },
            Data::Binary => Body::Binary { buf: Vec::new() },
            Data::Compressed => {
                let file = decompress_body(path, &mut input, &header)?;
                // The block is all the body: what follows it is known now.
                let tail = binary_tail(&mut input).map_err(|e| IoError::os(path, e))?;
                trailing(path, header.points, tail, None)?;
                Body::Columns {
                    file,
                    buf: Vec::new(),
                }
            }
        };
        let organised = header.organised();
        let info = SourceInfo {
            path: path.to_path_buf(),
            format: Format::Pcd,
            gzip,
            declared_count: Some(header.points),
            has_normals: wanted[3].is_some(),
            attributes: attribute_set(&wanted),
            header_bounds: None,
            las_transform: None,
        };
        Ok(PcdReader {
            info,
            input,
            admit: Admitter::new(path.to_path_buf(), policy),
            header,
            // A compressed body's end was checked above.
            ended: matches!(body, Body::Columns { .. }),
            organised,
            wanted,
            body,
            next: 0,
        })
    }

    fn truncated(&self, found: u64) -> IoError {
        IoError::Truncated {
            path: self.info.path.clone(),
            declared: self.header.points,
            found,
        }
    }

    fn read_ascii(&mut self, chunk: &mut PointChunk, want: u64) -> Result<(), IoError> {
        let Body::Ascii { line, line_no } = &mut self.body else {
            return Ok(());
        };
        let cols = self.wanted.map(|f| f.map(|i| self.header.column(i)));
        let names = slot_names();
        for _ in 0..want {
            let got = text::read_line(&mut self.input, line)
                .map_err(|e| IoError::os(&self.info.path, e))?;
            *line_no += 1;
            let bad = |reason: String| IoError::BadRecord {
                path: self.info.path.clone(),
                record: self.next,
                reason: format!("line {line_no}: {reason}"),
            };
            match got {
                Line::Eof => return Err(self.truncated(self.next)),
                Line::TooLong => return Err(bad(format!("longer than {} bytes", text::MAX_LINE))),
                Line::Unterminated => {
                    self.admit.cut(chunk, self.next, *line_no)?;
                    self.next += 1;
                    continue;
                }
                Line::Read => {}
            }
            let s = text::as_text(line).map_err(bad)?;
            let tokens: Vec<&str> = s.split_ascii_whitespace().collect();
            let mut v = [0.0f64; SLOTS];
            for (k, col) in cols.iter().enumerate() {
                let Some(c) = col else { continue };
                let tok = tokens
                    .get(*c)
                    .ok_or_else(|| bad(format!("{} values, expected more", tokens.len())))?;
                v[k] = text::parse_f64(tok, names[k]).map_err(bad)?;
            }
            v[RGB_SLOT] = f64::from(ascii_rgb_bits(v[RGB_SLOT]));
            let (p, n) = point(&v);
            match self.organised && is_no_return(p) {
                true => self.admit.no_return(chunk),
                false => {
                    let a = attribute_values(&v);
                    self.admit.push_with(chunk, self.next, p, n, &a)?
                }
            }
            self.next += 1;
        }
        Ok(())
    }

    fn read_binary(&mut self, chunk: &mut PointChunk, want: u64) -> Result<(), IoError> {
        let Body::Binary { buf } = &mut self.body else {
            return Ok(());
        };
        let size = self.header.record_bytes().max(1);
        let n = want.min((BLOCK_BYTES / size).max(1) as u64) as usize;
        buf.resize(n * size, 0);
        let got = read_full(&mut self.input, buf).map_err(|e| IoError::os(&self.info.path, e))?;
        let complete = got / size;
        let at = self
            .wanted
            .map(|f| f.map(|i| (self.header.offset(i), self.header.fields[i].scalar)));
        for (k, rec) in buf[..complete * size].chunks_exact(size).enumerate() {
            let mut v = at.map(|f| f.map_or(0.0, |(o, s)| value(&rec[o..], s)));
            if let Some((o, s)) = at[RGB_SLOT] {
                v[RGB_SLOT] = f64::from(rgb_bits(&rec[o..], s));
            }
            let (p, nrm) = point(&v);
            if self.organised && is_no_return(p) {
                self.admit.no_return(chunk);
                continue;
            }
            let a = attribute_values(&v);
            self.admit
                .push_with(chunk, self.next + k as u64, p, nrm, &a)?;
        }
        self.next += complete as u64;
        if complete < n {
            return Err(self.truncated(self.next));
        }
        Ok(())
    }

    fn read_columns(&mut self, chunk: &mut PointChunk, want: u64) -> Result<(), IoError> {
        let Body::Columns { file, buf } = &mut self.body else {
            return Ok(());
        };
        let n = want.min(BLOCK_BYTES as u64 / 8) as usize;
        let mut v = vec![[0.0f64; SLOTS]; n];
        let os = |e| IoError::os(&self.info.path, e);
        for (k, field) in self.wanted.iter().enumerate() {
            let Some(i) = *field else { continue };
            let f = &self.header.fields[i];
            // Column i starts after the earlier columns, for every point.
            let start = self.header.offset(i) as u64 * self.header.points;
            let size = f.scalar.size();
            buf.resize(n * size, 0);
            file.read_exact_at(buf, start + self.next * size as u64)
                .map_err(os)?;
            for (slot, b) in v.iter_mut().zip(buf.chunks_exact(size)) {
                slot[k] = match k {
                    RGB_SLOT => f64::from(rgb_bits(b, f.scalar)),
                    _ => value(b, f.scalar),
                };
            }
        }
        for (k, vals) in v.iter().enumerate() {
            let (p, nrm) = point(vals);
            if self.organised && is_no_return(p) {
                self.admit.no_return(chunk);
                continue;
            }
            let a = attribute_values(vals);
            self.admit
                .push_with(chunk, self.next + k as u64, p, nrm, &a)?;
        }
        self.next += n as u64;
        Ok(())
    }

    /// After the last record: nothing but blank lines (ASCII) or zero bytes
    /// (binary) may follow.
    fn check_end(&mut self) -> Result<(), IoError> {
        self.ended = true;
        let path = &self.info.path;
        let os = |e| IoError::os(path, e);
        match &mut self.body {
            Body::Ascii { line, line_no } => loop {
                let got = text::read_line(&mut self.input, line).map_err(os)?;
                if got == Line::Eof {
                    return Ok(());
                }
                *line_no += 1;
                if got == Line::TooLong || !line.iter().all(u8::is_ascii_whitespace) {
                    return Err(IoError::TrailingData {
                        path: path.clone(),
                        declared: self.header.points,
                        extra_bytes: None,
                        found: Trailing::Line {
                            line: *line_no,
                            declared: "points",
                        },
                    });
                }
            },
            Body::Binary { .. } => {
                let tail = binary_tail(&mut self.input).map_err(os)?;
                let record = self.header.record_bytes() as u64;
                trailing(path, self.header.points, tail, Some(record))
            }
            Body::Columns { .. } => Ok(()),
        }
    }
}

/// [`IoError::TrailingData`] when data (not zero padding) follows the
/// declared body; `record` is the record size of a binary body.
fn trailing(
    path: &Path,
    declared: u64,
    tail: Option<Tail>,
    record: Option<u64>,
) -> Result<(), IoError> {
    match tail {
        None => Ok(()),
        Some(t) => Err(IoError::TrailingData {
            path: path.to_path_buf(),
            declared,
            extra_bytes: Some(t.bytes),
            found: t.found(record),
        }),
    }
}

const FIELD_NAMES: [&str; 6] = ["x", "y", "z", "normal_x", "normal_y", "normal_z"];

/// Field names of the attribute slots, each with the names it goes by.
const ATTRIBUTE_FIELDS: [(Attribute, &[&str]); 5] = [
    (Attribute::Intensity, &["intensity"]),
    (Attribute::Rgb, &["rgb", "rgba"]),
    (Attribute::Classification, &["classification"]),
    (Attribute::ReturnNumber, &["return_number"]),
    (Attribute::GpsTime, &["gps_time"]),
];

fn slot_names() -> [&'static str; SLOTS] {
    let mut names = [""; SLOTS];
    names[..6].copy_from_slice(&FIELD_NAMES);
    for (k, (_, n)) in ATTRIBUTE_FIELDS.iter().enumerate() {
        names[6 + k] = n[0];
    }
    names
}

fn wanted_fields(h: &PcdHeader) -> Result<Wanted, String> {
    let mut w: Wanted = [None; SLOTS];
    for (k, name) in FIELD_NAMES.iter().enumerate() {
        w[k] = h.scalar_field(name);
    }
    if w[..3].iter().any(Option::is_none) {
        return Err("no x, y and z fields of one value each".into());
    }
    if w[3..6].iter().any(Option::is_none) {
        w[3..6].fill(None);
    }
    for (k, (_, names)) in ATTRIBUTE_FIELDS.iter().enumerate() {
        w[6 + k] = names.iter().find_map(|n| h.scalar_field(n));
    }
    // A packed colour is 4 bytes; any other `rgb` is not PCL's.
    if let Some(i) = w[RGB_SLOT] {
        if h.fields[i].scalar.size() != 4 {
            w[RGB_SLOT] = None;
        }
    }
    Ok(w)
}

fn attribute_set(w: &Wanted) -> AttributeSet {
    let present: Vec<Attribute> = ATTRIBUTE_FIELDS
        .iter()
        .enumerate()
        .filter(|(k, _)| w[6 + k].is_some())
        .map(|(_, (a, _))| *a)
        .collect();
    AttributeSet::of(&present)
}

fn attribute_values(v: &Values) -> AttributeValues {
    let bits = v[RGB_SLOT] as u32;
    let channel = |shift: u32| widen_8bit((bits >> shift) as u8);
    AttributeValues {
        intensity: to_unsigned(v[6], u16::MAX),
        rgb: [channel(16), channel(8), channel(0)],
        classification: to_unsigned(v[8], 255) as u8,
        return_number: to_unsigned(v[9], 255) as u8,
        gps_time: v[10],
    }
}

/// The 32 bits of a packed colour field (PCL stores them in an F 4 or U 4).
fn rgb_bits(b: &[u8], s: Scalar) -> u32 {
    match s.size() {
        4 => LittleEndian::read_u32(b),
        _ => 0,
    }
}

/// A packed colour written as text: PCL prints it as the unsigned integer
/// of its bits; older writers printed the float those bits make.
fn ascii_rgb_bits(v: f64) -> u32 {
    let integral = v.fract() == 0.0 && (0.0..=f64::from(u32::MAX)).contains(&v);
    match integral {
        true => v as u32,
        false => (v as f32).to_bits(),
    }
}

fn point(v: &Values) -> (DVec3, Vec3) {
    (
        DVec3::new(v[0], v[1], v[2]),
        Vec3::new(v[3] as f32, v[4] as f32, v[5] as f32),
    )
}

/// The first value of type `s` at the start of `b` (little-endian, as PCL
/// writes on every platform it runs on).
fn value(b: &[u8], s: Scalar) -> f64 {
    match s {
        Scalar::F(4) => f64::from(LittleEndian::read_f32(b)),
        Scalar::F(_) => LittleEndian::read_f64(b),
        Scalar::I(1) => f64::from(b[0] as i8),
        Scalar::I(2) => f64::from(LittleEndian::read_i16(b)),
        Scalar::I(4) => f64::from(LittleEndian::read_i32(b)),
        Scalar::I(_) => LittleEndian::read_i64(b) as f64,
        Scalar::U(1) => f64::from(b[0]),
        Scalar::U(2) => f64::from(LittleEndian::read_u16(b)),
        Scalar::U(4) => f64::from(LittleEndian::read_u32(b)),
        Scalar::U(_) => LittleEndian::read_u64(b) as f64,
    }
}

/// Reads the compressed body's sizes and decompresses it into an unnamed
/// temporary file.
fn decompress_body(path: &Path, input: &mut Input, h: &PcdHeader) -> Result<File, IoError> {
    let bad = |reason: String| IoError::BadRecord {
        path: path.to_path_buf(),
        record: 0,
        reason: format!("binary_compressed body: {reason}"),
    };
    let mut sizes = [0u8; 8];
    input
        .read_exact(&mut sizes)
        .map_err(|_| bad("no sizes".into()))?;
    let packed = u64::from(LittleEndian::read_u32(&sizes[..4]));
    let unpacked = u64::from(LittleEndian::read_u32(&sizes[4..]));
    let expected = (h.record_bytes() as u64).checked_mul(h.points);
    if expected != Some(unpacked) {
        return Err(bad(format!(
            "{unpacked} bytes uncompressed, but {} points of {} bytes are declared",
            h.points,
            h.record_bytes()
        )));
    }
    let file = tempfile::tempfile().map_err(|e| IoError::os(std::env::temp_dir(), e))?;
    let mut out = std::io::BufWriter::with_capacity(1 << 20, &file);
    lzf::decompress(&mut *input as &mut dyn BufRead, packed, &mut out, unpacked).map_err(bad)?;
    std::io::Write::flush(&mut out).map_err(|e| IoError::os(std::env::temp_dir(), e))?;
    drop(out);
    Ok(file)
}

impl PointReader for PcdReader {
    fn info(&self) -> &SourceInfo {
        &self.info
    }

    /// `max` of 0 is taken as 1, since 0 points read means end of input.
    fn read_chunk(&mut self, chunk: &mut PointChunk, max: usize) -> Result<usize, IoError> {
        let max = max.max(1);
        self.admit.begin(chunk, self.next, &self.info);
        while chunk.len() < max && self.next < self.header.points {
            let want = ((max - chunk.len()) as u64).min(self.header.points - self.next);
            match self.body {
                Body::Ascii { .. } => self.read_ascii(chunk, want)?,
                Body::Binary { .. } => self.read_binary(chunk, want)?,
                Body::Columns { .. } => self.read_columns(chunk, want)?,
            }
        }
        // Checked in the call that reads the last record, so a caller that
        // stops at the declared count still gets the check.
        if self.next == self.header.points && !self.ended {
            self.check_end()?;
        }
        Ok(self.admit.end(chunk))
    }

    fn skipped(&self) -> u64 {
        self.admit.skipped()
    }

    fn left_out(&self) -> LeftOut {
        LeftOut {
            no_return: self.admit.no_return_count(),
            unselected: 0,
        }
    }
}

/// A pixel of an organised cloud where the sensor saw nothing: PCL marks
/// it with NaN coordinates (an infinite one is not that, but invalid).
fn is_no_return(p: DVec3) -> bool {
    p.is_nan()
}

#[cfg(test)]
mod tests {
    use super::*;

    const ASCII: &str = "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nPOINTS 2\nDATA ascii\n";

    fn read(bytes: &[u8], policy: InvalidPolicy) -> Result<(Vec<DVec3>, u64), IoError> {
        let input: Input = Box::new(std::io::Cursor::new(bytes.to_vec()));
        let mut r = PcdReader::open(Path::new("t.pcd"), input, false, policy)?;
        let mut chunk = PointChunk::default();
        let mut all = Vec::new();
        while r.read_chunk(&mut chunk, 1)? > 0 {
            all.extend_from_slice(&chunk.xyz);
        }
        Ok((all, r.skipped()))
    }

    #[test]
    fn ascii_lines_after_the_points_or_a_cut_last_line_are_errors() {
        let ok = format!("{ASCII}1 2 3\n4 5 6\n\n");
        assert_eq!(
            read(ok.as_bytes(), InvalidPolicy::Reject).unwrap().0.len(),
            2
        );
        let more = format!("{ASCII}1 2 3\n4 5 6\n7 8 9\n");
        match read(more.as_bytes(), InvalidPolicy::Reject) {
            Err(e @ IoError::TrailingData { declared: 2, .. }) => {
                assert!(e.to_string().contains("line 9"), "{e}")
            }
            other => panic!("{other:?}"),
        }
        let cut = format!("{ASCII}1 2 3\n4 5 6.5");
        assert!(matches!(
            read(cut.as_bytes(), InvalidPolicy::Reject),
            Err(IoError::CutShort {
                record: 1,
                line: 8,
                ..
            })
        ));
        assert_eq!(read(cut.as_bytes(), InvalidPolicy::Skip).unwrap().1, 1);
    }

    #[test]
    fn binary_records_past_the_count_are_errors_zeros_are_padding() {
        let header = ASCII.replace("ascii", "binary");
        let body: Vec<u8> = (0..9).flat_map(|i| (i as f32).to_le_bytes()).collect();
        let mut bytes = header.clone().into_bytes();
        bytes.extend_from_slice(&body);
        match read(&bytes, InvalidPolicy::Reject) {
            Err(IoError::TrailingData {
                declared: 2,
                extra_bytes: Some(12),
                ..
            }) => {}
            other => panic!("{other:?}"),
        }
        let mut padded = header.into_bytes();
        padded.extend_from_slice(&body[..24]);
        padded.extend([0u8; 4096]);
        assert_eq!(read(&padded, InvalidPolicy::Reject).unwrap().0.len(), 2);
    }
}
