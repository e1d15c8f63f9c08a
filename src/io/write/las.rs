//! LAS / LAZ point writer, records written by scanmesh itself (the `las`
//! crate's writer recomputes the header from its own idea of a point and
//! refuses legal files, such as LAS 1.2 with return number 6). Two kinds
//! of output:
//!
//! - **A LAS input's points, as they came** ([`LasOutput::source`]): every
//!   record is the input's own bytes (every standard field, the extra
//!   bytes), followed by the normals and flags as described extra bytes;
//!   the file is the input's version and point format, with its VLRs and
//!   EVLRs ([`crate::io::las_file`]).
//! - **Points of other inputs, built from their attributes**: the point
//!   format asked for ([`LasOutput::point_format`]: 0-3, 6 or 7), or the
//!   smallest of LAS 1.2's 0-3 that holds the attributes when the largest
//!   values are known and fit (a store knows them: [`LasOutput::largest`]),
//!   else LAS 1.4 format 6 or 7 (colour), which hold every class and
//!   return number. A value the format cannot hold is an error naming the
//!   point, the value and the format that holds it, never truncated. The
//!   number of returns is not carried: it is written equal to the return
//!   number, the least value valid beside it.
//!
//! Quantisation follows the ASPRS LAS 1.2 specification (sec. 2.2, "X, Y and
//! Z scale factors / offsets"): `X = round((x - offset) / scale)` must fit an
//! i32. Without a given transform, [`choose_las_transform`] picks one from
//! the bounds; a point outside the i32 range is an error, never clamped.

use super::{check_chunk, open_output, Checked};
use crate::geom::Aabb;
use crate::io::las_extra::{plan, ExtraPlan, Wanted};
use crate::io::las_file::las_error;
use crate::io::las_file::{Frame, RecordHeader, Stats, Vlr, LASZIP};
use crate::io::{
    AtomicFile, Attribute, AttributeMaxima, AttributeValues, IoError, LasReason, LasSource,
    LasTransform, PointChunk, PointWriter, WriterSpec,
};
use byteorder::{ByteOrder, LittleEndian};
use glam::DVec3;
use laz::{LazItemRecordBuilder, LazVlr, ParLasZipCompressor};
use std::fs::File;
use std::io::{BufWriter, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Integer coordinates stay within +-2^30: half the i32 range is headroom
/// for points slightly outside the stated bounds.
const REACH: f64 = (1u64 << 30) as f64;
/// Finest scale chosen automatically (1 nm for metres); finer buys nothing
/// at the magnitudes where f64 coordinates have ~1e-10 relative precision.
const MIN_SCALE_EXP: i32 = -9;
/// Fields every point format has at the same place.
const INTENSITY_AT: usize = 12;
const RETURNS_AT: usize = 14;
/// Largest class and return number formats 0-5 hold (5 and 3 bits), and
/// the largest return number formats 6-10 hold (4 bits).
const MAX_LEGACY_CLASS: u8 = 31;
const MAX_LEGACY_RETURN: u8 = 7;
const MAX_RETURN: u8 = 15;

/// What a LAS/LAZ output is made from besides the [`WriterSpec`].
#[derive(Clone, Debug, Default)]
pub struct LasOutput {
    /// The LAS input whose points are written as they came: every chunk
    /// carries their records ([`crate::io::Attributes::las`]).
    pub source: Option<Arc<LasSource>>,
    /// The point format asked for, for points built from attributes (0-3
    /// or 6-7); `None` chooses the smallest that holds them. A LAS input
    /// is written in its own format.
    pub point_format: Option<u8>,
    /// The largest attribute values the points have, when known: formats
    /// 0-3 when they hold them, else LAS 1.4. Unknown, LAS 1.4 format 6
    /// or 7 is chosen (it holds every value).
    pub largest: Option<AttributeMaxima>,
}

/// Point format 0-3's or 6-7's layout: where the fields scanmesh fills are.
#[derive(Clone, Copy, Debug)]
struct Layout {
    format: u8,
    extended: bool,
    class_at: usize,
    gps_at: Option<usize>,
    rgb_at: Option<usize>,
}

impl Layout {
    fn of(format: u8) -> Option<Self> {
        let legacy = |gps_at, rgb_at| Layout {
            format,
            extended: false,
            class_at: 15,
            gps_at,
            rgb_at,
        };
        let extended = |rgb_at| Layout {
            format,
            extended: true,
            class_at: 16,
            gps_at: Some(22),
            rgb_at,
        };
        Some(match format {
            0 => legacy(None, None),
            1 => legacy(Some(20), None),
            2 => legacy(None, Some(20)),
            3 => legacy(Some(20), Some(28)),
            6 => extended(None),
            7 => extended(Some(30)),
            _ => return None,
        })
    }

    /// Bytes of a record without extra bytes.
    fn len(self) -> usize {
        match self.format {
            0 => 20,
            1 => 28,
            2 => 26,
            3 => 34,
            6 => 30,
            _ => 36,
        }
    }
}

/// The point format for these attributes: the smallest of 0-3 that holds
/// them, or of 6-7 when `largest` needs LAS 1.4 or is unknown (LAS 1.4
/// holds any class and return number, so no value is refused).
fn smallest_format(gps: bool, rgb: bool, largest: Option<AttributeMaxima>) -> u8 {
    let big = largest
        .is_none_or(|m| m.classification > MAX_LEGACY_CLASS || m.return_number > MAX_LEGACY_RETURN);
    match (big, gps, rgb) {
        (true, _, false) => 6,
        (true, _, true) => 7,
        (false, false, false) => 0,
        (false, true, false) => 1,
        (false, false, true) => 2,
        (false, true, true) => 3,
    }
}

/// A transform for points within `bounds`: offset = the centre rounded to
/// whole units, scale = the smallest power of ten that keeps every point of
/// the box within +-2^30 quanta of the offset.
pub fn choose_las_transform(bounds: &Aabb) -> Option<LasTransform> {
    if bounds.is_empty() || !bounds.min.is_finite() || !bounds.max.is_finite() {
        return None;
    }
    let offset = bounds.center().round();
    let reach = (bounds.max - offset)
        .abs()
        .max((bounds.min - offset).abs())
        .max_element();
    let mut exp = (reach / REACH).log10().ceil().max(f64::from(MIN_SCALE_EXP)) as i32;
    while reach / 10f64.powi(exp) > REACH {
        exp += 1;
    }
    Some(LasTransform {
        scale: DVec3::splat(10f64.powi(exp)),
        offset,
    })
}

/// Where the records come from.
enum Records {
    /// The input's own records, `len` bytes each, of point format `format`.
    Raw { len: usize, format: u8 },
    /// Built from the attributes in `layout`, quantised by `transform`.
    Built {
        layout: Layout,
        transform: LasTransform,
    },
}

/// The points' destination: the file, or LASzip's compressor over it.
/// The compressor is LASzip's parallel one: each chunk of a written
/// window (50,000 points) is compressed on its own thread, to the same
/// bytes as one after the other, since LASzip compresses every chunk
/// afresh.
enum Out {
    Las(BufWriter<File>),
    Laz(Box<ParLasZipCompressor<BufWriter<File>>>),
}

pub(crate) struct LasWriter {
    path: PathBuf,
    spec: WriterSpec,
    out: Option<Out>,
    /// Taken by `finish`; a writer dropped before leaves nothing.
    atomic: Option<AtomicFile>,
    frame: Frame,
    records: Records,
    extra: ExtraPlan,
    stats: Stats,
    buf: Vec<u8>,
}

fn unsupported(path: &Path, reason: String) -> IoError {
    IoError::Unsupported {
        path: path.to_path_buf(),
        reason,
    }
}

/// The LASzip VLR for records of `format` with `extra` extra bytes, and
/// the compressor's description of them.
fn laszip_vlr(path: &Path, format: u8, extra: u16) -> Result<(Vlr, LazVlr), IoError> {
    let laz_err = |e: laz::LasZipError| las_error(path, las::Error::from(e));
    let items =
        LazItemRecordBuilder::default_for_point_format_id(format, extra).map_err(laz_err)?;
    let laz = LazVlr::from_laz_items(items);
    let mut data = Vec::new();
    laz.write_to(&mut data).map_err(|e| IoError::os(path, e))?;
    let header = RecordHeader::new(LASZIP, LazVlr::DESCRIPTION);
    Ok((Vlr { header, data }, laz))
}

/// The transform of points built from attributes: the spec's, or one
/// chosen from its bounds.
fn built_transform(path: &Path, spec: &WriterSpec) -> Result<LasTransform, IoError> {
    let las_fail = |reason| IoError::Las {
        path: path.to_path_buf(),
        reason: Box::new(reason),
    };
    let transform = match (spec.las_transform, &spec.bounds) {
        (Some(t), _) => t,
        (None, Some(b)) => {
            choose_las_transform(b).ok_or_else(|| las_fail(LasReason::EmptyBounds))?
        }
        (None, None) => return Err(las_fail(LasReason::NoBoundsOrTransform)),
    };
    let valid = transform.scale.is_finite()
        && transform.scale.cmpgt(DVec3::ZERO).all()
        && transform.offset.is_finite();
    match valid {
        true => Ok(transform),
        false => Err(las_fail(LasReason::BadTransform)),
    }
}

/// The layout of built records: the format asked for, which must be one
/// scanmesh builds and hold the spec's attributes, or the smallest.
fn built_layout(path: &Path, spec: &WriterSpec, las: &LasOutput) -> Result<Layout, IoError> {
    let gps = spec.attributes.contains(Attribute::GpsTime);
    let rgb = spec.attributes.contains(Attribute::Rgb);
    let Some(format) = las.point_format else {
        let format = smallest_format(gps, rgb, las.largest);
        return Layout::of(format)
            .ok_or_else(|| unsupported(path, format!("point format {format}")));
    };
    let layout = Layout::of(format).ok_or_else(|| {
        unsupported(
            path,
            format!("scanmesh writes LAS point formats 0-3 and 6-7 from attributes, not {format}"),
        )
    })?;
    let lacks = match (
        gps && layout.gps_at.is_none(),
        rgb && layout.rgb_at.is_none(),
    ) {
        (true, _) => Some("GPS time"),
        (_, true) => Some("colour"),
        _ => None,
    };
    match lacks {
        Some(what) => Err(unsupported(
            path,
            format!(
                "LAS point format {format} holds no {what}; point format {} does",
                smallest_format(gps, rgb, las.largest).max(format)
            ),
        )),
        None => Ok(layout),
    }
}

impl LasWriter {
    pub fn create(
        path: &Path,
        spec: &WriterSpec,
        las: &LasOutput,
        compressed: bool,
    ) -> Result<Self, IoError> {
        let (records, frame, extra, laz) = match &las.source {
            Some(source) => Self::as_it_came(path, spec, las, source, compressed)?,
            None => Self::built(path, spec, las, compressed)?,
        };
        let (atomic, out) = open_output(path)?;
        let mut w = LasWriter {
            path: path.to_path_buf(),
            spec: spec.clone(),
            out: None,
            atomic: Some(atomic),
            frame,
            records,
            extra,
            stats: Stats::default(),
            buf: Vec::new(),
        };
        w.start(out, laz)?;
        Ok(w)
    }

    /// Writes the header and VLRs (the header a placeholder until
    /// `finish`) and readies the points' destination.
    fn start(&mut self, mut out: BufWriter<File>, laz: Option<LazVlr>) -> Result<(), IoError> {
        let path = self.path.clone();
        self.frame
            .write_head(&mut out)
            .map_err(|e| las_error(&path, e))?;
        self.out = Some(match laz {
            None => Out::Las(out),
            Some(vlr) => Out::Laz(Box::new(
                ParLasZipCompressor::new(out, vlr)
                    .map_err(|e| las_error(&path, las::Error::from(e)))?,
            )),
        });
        Ok(())
    }

    /// The records, frame and extra bytes of a LAS input written as it
    /// came.
    fn as_it_came(
        path: &Path,
        spec: &WriterSpec,
        las: &LasOutput,
        source: &LasSource,
        compressed: bool,
    ) -> Result<(Records, Frame, ExtraPlan, Option<LazVlr>), IoError> {
        let format = source.point_format();
        if let Some(asked) = las.point_format.filter(|&f| f != format) {
            return Err(unsupported(
                path,
                format!("a LAS input is written in its own point format ({format}), not {asked}"),
            ));
        }
        let base = las::point::Format::new(format)
            .map_err(|e| las_error(path, e))?
            .len();
        let len = source.record_len();
        let cannot =
            |why: String| unsupported(path, format!("cannot extend the input's records: {why}"));
        let extra_in = len.checked_sub(base).ok_or_else(|| {
            cannot(format!(
                "records of {len} bytes are shorter than format {format}'s"
            ))
        })?;
        let extra = plan(
            usize::from(base),
            usize::from(extra_in),
            source.extra_bytes_vlr(),
            Wanted::of(spec),
        )
        .map_err(cannot)?;
        if extra.vlr.is_some() && source.extra_bytes_in_evlrs() {
            return Err(cannot("its Extra Bytes record is an EVLR".into()));
        }
        let added = extra.record_len - base;
        let (laszip, laz) = match compressed {
            true => {
                let (vlr, laz) = laszip_vlr(path, format, added)?;
                (Some(vlr), Some(laz))
            }
            false => (None, None),
        };
        let frame = source.frame(extra.record_len, extra.vlr.clone(), laszip);
        let records = Records::Raw {
            len: usize::from(len),
            format,
        };
        Ok((records, frame, extra, laz))
    }

    /// The records, frame and extra bytes of points built from their
    /// attributes.
    fn built(
        path: &Path,
        spec: &WriterSpec,
        las: &LasOutput,
        compressed: bool,
    ) -> Result<(Records, Frame, ExtraPlan, Option<LazVlr>), IoError> {
        let transform = built_transform(path, spec)?;
        let layout = built_layout(path, spec, las)?;
        let base = layout.len();
        let extra = plan(base, 0, None, Wanted::of(spec)).map_err(|e| unsupported(path, e))?;
        let added = extra.record_len - base as u16;
        let mut vlrs: Vec<Vlr> = extra.vlr.iter().cloned().collect();
        let laz = match compressed {
            true => {
                let (vlr, laz) = laszip_vlr(path, layout.format, added)?;
                vlrs.push(vlr);
                Some(laz)
            }
            false => None,
        };
        let version = match layout.extended {
            true => las::Version::new(1, 4),
            false => las::Version::new(1, 2),
        };
        let format_byte = layout.format | if compressed { 0x80 } else { 0 };
        let mut frame = Frame::new(version, format_byte, extra.record_len, vlrs);
        let h = &mut frame.header;
        (h.x_scale_factor, h.y_scale_factor, h.z_scale_factor) =
            (transform.scale.x, transform.scale.y, transform.scale.z);
        (h.x_offset, h.y_offset, h.z_offset) =
            (transform.offset.x, transform.offset.y, transform.offset.z);
        Ok((Records::Built { layout, transform }, frame, extra, laz))
    }
}

/// Integer coordinates of output record `record`, or an error naming it.
fn quantise(t: &LasTransform, path: &Path, p: DVec3, record: u64) -> Result<[i32; 3], IoError> {
    let q = ((p - t.offset) / t.scale).round();
    let range = f64::from(i32::MIN)..=f64::from(i32::MAX);
    if range.contains(&q.x) && range.contains(&q.y) && range.contains(&q.z) {
        return Ok([q.x as i32, q.y as i32, q.z as i32]);
    }
    Err(IoError::Las {
        path: path.to_path_buf(),
        reason: Box::new(LasReason::OutOfRange {
            record,
            point: p,
            scale: t.scale,
            offset: t.offset,
        }),
    })
}

/// Checks that `layout` holds point `record`'s class and return number;
/// `wide` is the LAS 1.4 format that would (6, or 7 with colour).
fn check_fits(
    path: &Path,
    layout: Layout,
    wide: u8,
    record: u64,
    a: &AttributeValues,
) -> Result<(), IoError> {
    let (max_class, max_return) = match layout.extended {
        true => (u8::MAX, MAX_RETURN),
        false => (MAX_LEGACY_CLASS, MAX_LEGACY_RETURN),
    };
    let too_big = |field: &'static str, value: u8, max: u8| IoError::LasValue {
        path: path.to_path_buf(),
        record,
        field,
        value: u32::from(value),
        format: layout.format,
        max: u32::from(max),
        holds: (value <= MAX_RETURN || field == "class").then_some(wide),
    };
    if a.classification > max_class {
        return Err(too_big("class", a.classification, max_class));
    }
    if a.return_number > max_return {
        return Err(too_big("return number", a.return_number, max_return));
    }
    Ok(())
}

/// Fills `rec` (zeroed) with point `p`'s fields in `layout`.
fn build_record(
    rec: &mut [u8],
    layout: Layout,
    q: [i32; 3],
    a: &AttributeValues,
    spec: &WriterSpec,
) {
    LittleEndian::write_i32_into(&q, &mut rec[..12]);
    let has = |x| spec.attributes.contains(x);
    if has(Attribute::Intensity) {
        LittleEndian::write_u16(&mut rec[INTENSITY_AT..], a.intensity);
    }
    // Return r of r: 1 of 1 when the input has no return numbers.
    let r = match has(Attribute::ReturnNumber) {
        true => a.return_number,
        false => 1,
    };
    rec[RETURNS_AT] = match layout.extended {
        true => r | (r << 4),
        false => r | (r << 3),
    };
    rec[layout.class_at] = a.classification;
    if let (Some(at), true) = (layout.gps_at, has(Attribute::GpsTime)) {
        LittleEndian::write_f64(&mut rec[at..], a.gps_time);
    }
    if let (Some(at), true) = (layout.rgb_at, has(Attribute::Rgb)) {
        LittleEndian::write_u16_into(&a.rgb, &mut rec[at..at + 6]);
    }
}

/// The return number field of a record of point `format`.
#[inline]
fn return_number(rec: &[u8], format: u8) -> u8 {
    match format {
        0..=5 => rec[RETURNS_AT] & 7,
        _ => rec[RETURNS_AT] & 15,
    }
}

impl LasWriter {
    /// Fills the output records of `chunk` into `self.buf`.
    fn fill(&mut self, chunk: &PointChunk, c: &Checked) -> Result<(), IoError> {
        let n = chunk.len();
        let out_len = usize::from(self.extra.record_len);
        self.buf.clear();
        self.buf.resize(n * out_len, 0);
        let first = self.stats.count;
        for (i, rec) in self.buf.chunks_exact_mut(out_len).enumerate() {
            let (q, ret) = match &self.records {
                Records::Raw { len, format } => {
                    let input = chunk.attrs.las.get(i);
                    rec[..*len].copy_from_slice(input);
                    let mut q = [0i32; 3];
                    LittleEndian::read_i32_into(&input[..12], &mut q);
                    (q, return_number(input, *format))
                }
                Records::Built { layout, transform } => {
                    let record = first + i as u64;
                    let a = chunk.attrs.get(i);
                    let wide = match layout.rgb_at {
                        Some(_) => 7,
                        None => 6,
                    };
                    check_fits(&self.path, *layout, wide, record, &a)?;
                    let q = quantise(transform, &self.path, chunk.xyz[i], record)?;
                    build_record(rec, *layout, q, &a, &self.spec);
                    (q, return_number(rec, layout.format))
                }
            };
            if let (Some(at), Some(ns)) = (self.extra.normals_at, c.normals) {
                LittleEndian::write_f32_into(&ns[i].to_array(), &mut rec[at..at + 12]);
            }
            for (&at, v) in self.extra.values_at.iter().zip(c.values_of(i)) {
                LittleEndian::write_f32(&mut rec[at..at + 4], *v);
            }
            if let (Some(at), Some(fs)) = (self.extra.flags_at, c.flags) {
                rec[at] = fs[i];
            }
            self.stats.add(q, ret);
        }
        Ok(())
    }

    /// Checks that a chunk written as it came carries its records.
    fn check_records(&self, chunk: &PointChunk) -> Result<(), IoError> {
        let Records::Raw { len, .. } = self.records else {
            return Ok(());
        };
        let las = &chunk.attrs.las;
        if las.record_len == len && las.len() == chunk.len() && las.bytes.len() == len * chunk.len()
        {
            return Ok(());
        }
        Err(unsupported(
            &self.path,
            format!(
                "writer needs {} input records of {len} bytes for this chunk, it has {} of {}",
                chunk.len(),
                las.len(),
                las.record_len
            ),
        ))
    }
}

impl PointWriter for LasWriter {
    fn write_chunk(&mut self, chunk: &PointChunk, flags: Option<&[u8]>) -> Result<(), IoError> {
        let c = check_chunk(&self.path, &self.spec, chunk, flags, self.stats.count)?;
        self.check_records(chunk)?;
        self.fill(chunk, &c)?;
        let path = &self.path;
        let written = match &mut self.out {
            Some(Out::Las(w)) => w.write_all(&self.buf),
            Some(Out::Laz(z)) => z.compress_many(&self.buf),
            None => return Err(unsupported(path, "writer already finished".into())),
        };
        written.map_err(|e| IoError::os(path, e))
    }

    fn finish(mut self: Box<Self>) -> Result<u64, IoError> {
        let path = self.path.clone();
        let os = |e| IoError::os(&path, e);
        super::check_count(&path, &self.spec, self.stats.count)?;
        let (Some(out), Some(atomic)) = (self.out.take(), self.atomic.take()) else {
            return Err(unsupported(&path, "writer already finished".into()));
        };
        let mut out = match out {
            Out::Las(w) => w,
            Out::Laz(mut z) => {
                z.done()
                    .map_err(|e| las_error(&path, las::Error::from(e)))?;
                z.into_inner()
            }
        };
        let end = out.stream_position().map_err(os)?;
        let evlrs = self.frame.write_evlrs(&mut out, end).map_err(os)?;
        self.frame.finish(&self.stats, &evlrs);
        out.seek(SeekFrom::Start(0)).map_err(os)?;
        self.frame
            .write_head(&mut out)
            .map_err(|e| las_error(&path, e))?;
        out.into_inner().map_err(|e| os(e.into_error()))?;
        atomic.commit()?;
        Ok(self.stats.count)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_smallest_format_holds_the_attributes_and_the_values() {
        let big_class = AttributeMaxima {
            classification: 65,
            ..Default::default()
        };
        let return_6 = AttributeMaxima {
            return_number: 6,
            ..Default::default()
        };
        let small = Some(AttributeMaxima::default());
        assert_eq!(smallest_format(false, false, small), 0);
        assert_eq!(smallest_format(true, true, small), 3);
        assert_eq!(smallest_format(true, false, None), 6);
        assert_eq!(smallest_format(false, true, None), 7);
        assert_eq!(smallest_format(true, false, Some(return_6)), 1);
        assert_eq!(smallest_format(false, false, Some(big_class)), 6);
        assert_eq!(smallest_format(false, true, Some(big_class)), 7);
        for f in [0, 1, 2, 3, 6, 7] {
            let l = Layout::of(f).unwrap();
            assert_eq!(
                l.len(),
                usize::from(las::point::Format::new(f).unwrap().len()),
                "format {f}"
            );
        }
    }
}
