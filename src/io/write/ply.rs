//! PLY point writer: binary (little- or big-endian) or ASCII; `x y z` as
//! double, `nx ny nz` as float, the spec's computed values as float, `flags`
//! as uchar. The vertex count is written
//! as a fixed-width placeholder and patched in `finish`, so the points
//! stream straight to disk (a count the spec declares is written as it is,
//! and checked in `finish`).
//!
//! Attributes follow: `intensity` ushort, `red green blue` uchar (the type
//! every PLY viewer reads; 16-bit colour keeps its high byte),
//! `classification` and `return_number` uchar, `gps_time` double.
//!
//! Binary PCD (PCL's format) has the same records under another header
//! (`FIELDS x y z normal_x normal_y normal_z flags`, `DATA binary`, counts
//! in `WIDTH` and `POINTS`), so this writer writes it too; its attributes
//! take PCL's types where PCL has one (`intensity` F 4 as in `PointXYZI`,
//! `rgb` packed 0x00RRGGBB in an F 4 as in `PointXYZRGB`).

use super::{check_chunk, open_output, Checked};
use crate::io::attributes::narrow_16bit;
use crate::io::{
    AtomicFile, Attribute, AttributeSet, Attributes, Format, IoError, PointChunk, PointWriter,
    WriterSpec,
};
use byteorder::{BigEndian, ByteOrder, LittleEndian};
use rayon::prelude::*;
use std::fs::File;
use std::io::{BufWriter, Seek, SeekFrom, Write};
use std::ops::Range;
use std::path::{Path, PathBuf};

/// Digits of the vertex count: any u64 fits, zero-padded.
const COUNT_WIDTH: usize = 20;

pub(crate) struct PlyWriter {
    path: PathBuf,
    spec: WriterSpec,
    // Declared before `atomic`: dropped (flushed into the temp) first.
    out: BufWriter<File>,
    atomic: AtomicFile,
    /// Byte offsets of the count placeholders.
    count_at: Vec<u64>,
    count: u64,
    /// Encoded parts of the current chunk.
    bufs: Vec<Vec<u8>>,
}

/// The header text and the byte offsets of its count digits.
fn header(spec: &WriterSpec) -> (String, Vec<u64>) {
    if spec.format == Format::Pcd {
        return pcd_header(spec);
    }
    let format = match spec.format {
        Format::PlyAscii => "ascii",
        Format::PlyBinaryBe => "binary_big_endian",
        _ => "binary_little_endian",
    };
    let comment = spec.comment.unwrap_or("written by scanmesh");
    let mut h = format!("ply\nformat {format} 1.0\ncomment {comment}\nelement vertex ");
    let count_at = match spec.count {
        Some(n) => {
            h += &format!("{n}\n");
            Vec::new()
        }
        None => {
            let at = h.len() as u64;
            h += &format!("{:0w$}\n", 0, w = COUNT_WIDTH);
            vec![at]
        }
    };
    h += "property double x\nproperty double y\nproperty double z\n";
    if spec.with_normals {
        h += "property float nx\nproperty float ny\nproperty float nz\n";
    }
    for v in spec.values {
        h += &format!("property float {}\n", v.name);
    }
    if spec.with_flags {
        h += "property uchar flags\n";
    }
    for a in spec.attributes.iter() {
        h += match a {
            Attribute::Intensity => "property ushort intensity\n",
            Attribute::Rgb => "property uchar red\nproperty uchar green\nproperty uchar blue\n",
            Attribute::Classification => "property uchar classification\n",
            Attribute::ReturnNumber => "property uchar return_number\n",
            Attribute::GpsTime => "property double gps_time\n",
        };
    }
    h += "end_header\n";
    (h, count_at)
}

fn pcd_header(spec: &WriterSpec) -> (String, Vec<u64>) {
    let (mut fields, mut size, mut kind) = (
        "x y z".to_string(),
        "8 8 8".to_string(),
        "F F F".to_string(),
    );
    let mut count = "1 1 1".to_string();
    let mut add = |name: &str, s: &str, t: &str| {
        fields += &format!(" {name}");
        size += &format!(" {s}");
        kind += &format!(" {t}");
        count += " 1";
    };
    if spec.with_normals {
        for n in ["normal_x", "normal_y", "normal_z"] {
            add(n, "4", "F");
        }
    }
    for v in spec.values {
        add(v.name, "4", "F");
    }
    if spec.with_flags {
        add("flags", "1", "U");
    }
    for a in spec.attributes.iter() {
        match a {
            Attribute::Intensity => add("intensity", "4", "F"),
            Attribute::Rgb => add("rgb", "4", "F"),
            Attribute::Classification => add("classification", "1", "U"),
            Attribute::ReturnNumber => add("return_number", "1", "U"),
            Attribute::GpsTime => add("gps_time", "8", "F"),
        }
    }
    let comment = match spec.comment {
        Some(c) => format!("# {c}\n"),
        None => String::new(),
    };
    let mut h = format!(
        "# .PCD v0.7 - Point Cloud Data file format (written by scanmesh)\n{comment}VERSION 0.7\n\
         FIELDS {fields}\nSIZE {size}\nTYPE {kind}\nCOUNT {count}\nWIDTH "
    );
    let width_at = h.len() as u64;
    h += &format!(
        "{:0w$}\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS ",
        0,
        w = PCD_COUNT_WIDTH
    );
    let points_at = h.len() as u64;
    h += &format!("{:0w$}\nDATA binary\n", 0, w = PCD_COUNT_WIDTH);
    (h, vec![width_at, points_at])
}

/// Digits of PCD's counts: PCL reads them as 32-bit integers.
const PCD_COUNT_WIDTH: usize = 10;

impl PlyWriter {
    pub fn create(path: &Path, spec: &WriterSpec) -> Result<Self, IoError> {
        let (atomic, mut out) = open_output(path)?;
        let (text, count_at) = header(spec);
        out.write_all(text.as_bytes())
            .map_err(|e| IoError::os(path, e))?;
        Ok(PlyWriter {
            path: path.to_path_buf(),
            spec: spec.clone(),
            out,
            atomic,
            count_at,
            count: 0,
            bufs: Vec::new(),
        })
    }
}

/// Points per encoding task: big enough to amortise a task, small enough
/// that both threads get work on a window.
const ENCODE_PART: usize = 1 << 16;

/// Encodes the chunk in parts on rayon's threads, each into its own buffer
/// of `bufs` (kept between chunks); written in order, the parts are the
/// sequential encoding byte for byte.
fn encode_parts(bufs: &mut Vec<Vec<u8>>, chunk: &PointChunk, c: &Checked, format: Format) {
    let parts = chunk.len().div_ceil(ENCODE_PART);
    bufs.resize_with(parts.max(bufs.len()), Vec::new);
    bufs.par_iter_mut().enumerate().for_each(|(k, buf)| {
        buf.clear();
        let range = k * ENCODE_PART..((k + 1) * ENCODE_PART).min(chunk.len());
        if range.is_empty() {
            return;
        }
        let pcd = format == Format::Pcd;
        match format {
            Format::PlyAscii => encode_text(buf, chunk, c, range),
            Format::PlyBinaryBe => encode_binary::<BigEndian>(buf, chunk, c, range, pcd),
            _ => encode_binary::<LittleEndian>(buf, chunk, c, range, pcd),
        }
    });
}

fn encode_binary<B: ByteOrder>(
    buf: &mut Vec<u8>,
    chunk: &PointChunk,
    c: &Checked,
    range: Range<usize>,
    pcd: bool,
) {
    let mut b8 = [0u8; 8];
    for (i, p) in range.clone().zip(&chunk.xyz[range]) {
        for v in [p.x, p.y, p.z] {
            B::write_f64(&mut b8, v);
            buf.extend_from_slice(&b8);
        }
        if let Some(n) = c.normals {
            for v in [n[i].x, n[i].y, n[i].z] {
                B::write_f32(&mut b8, v);
                buf.extend_from_slice(&b8[..4]);
            }
        }
        for &v in c.values_of(i) {
            B::write_f32(&mut b8, v);
            buf.extend_from_slice(&b8[..4]);
        }
        if let Some(f) = c.flags {
            buf.push(f[i]);
        }
        if let Some(a) = c.attrs {
            match pcd {
                false => encode_attrs_ply::<B>(buf, a, c.set, i),
                true => encode_attrs_pcd(buf, a, c.set, i),
            }
        }
    }
}

fn encode_attrs_ply<B: ByteOrder>(buf: &mut Vec<u8>, a: &Attributes, set: AttributeSet, i: usize) {
    let mut b8 = [0u8; 8];
    for attr in set.iter() {
        match attr {
            Attribute::Intensity => {
                B::write_u16(&mut b8, a.intensity[i]);
                buf.extend_from_slice(&b8[..2]);
            }
            Attribute::Rgb => buf.extend(a.rgb[i].map(narrow_16bit)),
            Attribute::Classification => buf.push(a.classification[i]),
            Attribute::ReturnNumber => buf.push(a.return_number[i]),
            Attribute::GpsTime => {
                B::write_f64(&mut b8, a.gps_time[i]);
                buf.extend_from_slice(&b8);
            }
        }
    }
}

/// PCD is little-endian only; the record layout of [`pcd_header`].
fn encode_attrs_pcd(buf: &mut Vec<u8>, a: &Attributes, set: AttributeSet, i: usize) {
    for attr in set.iter() {
        match attr {
            Attribute::Intensity => buf.extend(f32::from(a.intensity[i]).to_le_bytes()),
            Attribute::Rgb => buf.extend(pack_rgb(a.rgb[i]).to_le_bytes()),
            Attribute::Classification => buf.push(a.classification[i]),
            Attribute::ReturnNumber => buf.push(a.return_number[i]),
            Attribute::GpsTime => buf.extend(a.gps_time[i].to_le_bytes()),
        }
    }
}

/// PCL's packed colour: 0x00RRGGBB, 8 bits per channel.
pub(crate) fn pack_rgb(rgb: [u16; 3]) -> u32 {
    let [r, g, b] = rgb.map(|v| u32::from(narrow_16bit(v)));
    (r << 16) | (g << 8) | b
}

/// One line per point; `{}` prints the shortest text that parses back to
/// the same f64 (f32 for normals).
pub(crate) fn encode_text(buf: &mut Vec<u8>, chunk: &PointChunk, c: &Checked, range: Range<usize>) {
    for (i, p) in range.clone().zip(&chunk.xyz[range]) {
        // Writing into a Vec cannot fail.
        let _ = write!(buf, "{} {} {}", p.x, p.y, p.z);
        if let Some(n) = c.normals {
            let _ = write!(buf, " {} {} {}", n[i].x, n[i].y, n[i].z);
        }
        for v in c.values_of(i) {
            let _ = write!(buf, " {v}");
        }
        if let Some(f) = c.flags {
            let _ = write!(buf, " {}", f[i]);
        }
        if let Some(a) = c.attrs {
            encode_attrs_text(buf, a, c.set, i);
        }
        buf.push(b'\n');
    }
}

fn encode_attrs_text(buf: &mut Vec<u8>, a: &Attributes, set: AttributeSet, i: usize) {
    for attr in set.iter() {
        let _ = match attr {
            Attribute::Intensity => write!(buf, " {}", a.intensity[i]),
            Attribute::Rgb => {
                let [r, g, b] = a.rgb[i].map(narrow_16bit);
                write!(buf, " {r} {g} {b}")
            }
            Attribute::Classification => write!(buf, " {}", a.classification[i]),
            Attribute::ReturnNumber => write!(buf, " {}", a.return_number[i]),
            Attribute::GpsTime => write!(buf, " {}", a.gps_time[i]),
        };
    }
}

impl PointWriter for PlyWriter {
    fn write_chunk(&mut self, chunk: &PointChunk, flags: Option<&[u8]>) -> Result<(), IoError> {
        let c = check_chunk(&self.path, &self.spec, chunk, flags, self.count)?;
        encode_parts(&mut self.bufs, chunk, &c, self.spec.format);
        for buf in &self.bufs {
            self.out
                .write_all(buf)
                .map_err(|e| IoError::os(&self.path, e))?;
        }
        self.count += chunk.len() as u64;
        Ok(())
    }

    fn finish(self: Box<Self>) -> Result<u64, IoError> {
        let PlyWriter {
            path,
            spec,
            out,
            atomic,
            count_at,
            count,
            ..
        } = *self;
        super::check_count(&path, &spec, count)?;
        let os = |e| IoError::os(&path, e);
        let width = if spec.format == Format::Pcd {
            if count > u64::from(u32::MAX >> 1) {
                return Err(IoError::Unsupported {
                    path,
                    reason: format!("{count} points are more than PCD's 32-bit counts hold"),
                });
            }
            PCD_COUNT_WIDTH
        } else {
            COUNT_WIDTH
        };
        let mut file = out.into_inner().map_err(|e| os(e.into_error()))?;
        for at in count_at {
            file.seek(SeekFrom::Start(at)).map_err(os)?;
            file.write_all(format!("{count:0width$}").as_bytes())
                .map_err(os)?;
        }
        drop(file);
        atomic.commit()?;
        Ok(count)
    }
}
