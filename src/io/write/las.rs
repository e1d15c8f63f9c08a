//! LAS 1.2 / LAZ point writer, point data format 0 to 3 (x y z as scaled
//! i32; format 1 adds GPS time, 2 colour, 3 both: the smallest that holds the
//! attributes asked for). Intensity, classification and return number are in
//! every format; classification takes 5 bits in formats 0-3, so a larger
//! class is an error naming the point, never truncated. The number of
//! returns is not carried: it is written equal to the return number (1 when
//! there is none), the least value valid beside it. The per-point flags,
//! when asked for, go to the "user data" byte; normals go to three float
//! "extra bytes" after the record, described by an Extra Bytes VLR
//! ([`crate::io::las_extra`]).
//!
//! Quantisation follows the ASPRS LAS 1.2 specification (sec. 2.2, "X, Y and
//! Z scale factors / offsets"): `X = round((x - offset) / scale)` must fit an
//! i32. Without a given transform, [`choose_las_transform`] picks one from
//! the bounds; a point outside the i32 range is an error, never clamped.

use super::{check_chunk, open_output};
use crate::geom::Aabb;
use crate::io::las::las_error;
use crate::io::las_extra::{normals_vlr, NORMAL_BYTES};
use crate::io::{
    AtomicFile, Attribute, AttributeSet, IoError, LasTransform, PointChunk, PointWriter, WriterSpec,
};
use byteorder::{ByteOrder, LittleEndian};
use glam::DVec3;
use las::{point::Format, Builder, PointData, PointDataBuilder, Transform, Vector, Writer};
use std::fs::File;
use std::io::{self, BufWriter, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// Integer coordinates stay within +-2^30: half the i32 range is headroom
/// for points slightly outside the stated bounds.
const REACH: f64 = (1u64 << 30) as f64;
/// Finest scale chosen automatically (1 nm for metres); finer buys nothing
/// at the magnitudes where f64 coordinates have ~1e-10 relative precision.
const MIN_SCALE_EXP: i32 = -9;
/// Point format 0-3 records: x y z i32, intensity u16, return bits, class,
/// scan angle, user data, point source id; then GPS time (formats 1, 3) and
/// colour (2 at 20, 3 at 28).
const INTENSITY_AT: usize = 12;
const RETURNS_AT: usize = 14;
const CLASS_AT: usize = 15;
const USER_DATA_AT: usize = 17;
const GPS_AT: usize = 20;
/// Largest class formats 0-3 hold (5 bits).
const MAX_CLASS: u8 = 31;

/// The point format for `set`, and where its GPS time and colour sit.
fn point_format(set: AttributeSet) -> (u8, Option<usize>, Option<usize>) {
    match (
        set.contains(Attribute::GpsTime),
        set.contains(Attribute::Rgb),
    ) {
        (false, false) => (0, None, None),
        (true, false) => (1, Some(GPS_AT), None),
        (false, true) => (2, None, Some(20)),
        (true, true) => (3, Some(GPS_AT), Some(28)),
    }
}

/// Largest return number a LAS 1.2 header counts (points by return 1-5).
const MAX_RETURN: u8 = 5;

/// Return number r of r (bits 0-2 and 3-5); 1 of 1 when unknown.
fn returns_byte(r: Option<u8>) -> u8 {
    let r = r.unwrap_or(1);
    r | (r << 3)
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

/// The output file as the `las` writer sees it. Once `abandoned`, writes and
/// seeks succeed without touching the file: the `las` writer finalises itself
/// on drop and panics if that fails, which must not happen for a file that is
/// being removed anyway. The position is tracked in both modes, because the
/// LAZ compressor does arithmetic on it.
struct Guarded {
    out: BufWriter<File>,
    abandoned: Arc<AtomicBool>,
    pos: u64,
    len: u64,
}

impl Guarded {
    fn is_abandoned(&self) -> bool {
        self.abandoned.load(Ordering::Relaxed)
    }
}

impl Write for Guarded {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        let n = match self.is_abandoned() {
            true => buf.len(),
            false => self.out.write(buf)?,
        };
        self.pos += n as u64;
        self.len = self.len.max(self.pos);
        Ok(n)
    }
    fn flush(&mut self) -> io::Result<()> {
        match self.is_abandoned() {
            true => Ok(()),
            false => self.out.flush(),
        }
    }
}

impl Seek for Guarded {
    fn seek(&mut self, to: SeekFrom) -> io::Result<u64> {
        let target = match to {
            SeekFrom::Start(p) => Some(p),
            SeekFrom::Current(d) => self.pos.checked_add_signed(d),
            SeekFrom::End(d) => self.len.checked_add_signed(d),
        };
        let target = target.ok_or_else(|| io::Error::from(io::ErrorKind::InvalidInput))?;
        if !self.is_abandoned() {
            self.out.seek(SeekFrom::Start(target))?;
        }
        self.pos = target;
        Ok(target)
    }
}

pub(crate) struct LasWriter {
    path: PathBuf,
    spec: WriterSpec,
    writer: Option<Writer<Guarded>>,
    /// Taken by `finish`; dropped after `writer` otherwise (field order).
    atomic: Option<AtomicFile>,
    abandoned: Arc<AtomicBool>,
    transform: LasTransform,
    data: PointData,
    record_len: usize,
    gps_at: Option<usize>,
    rgb_at: Option<usize>,
    count: u64,
}

fn to_vector(t: &LasTransform) -> Vector<Transform> {
    let axis = |s: f64, o: f64| Transform {
        scale: s,
        offset: o,
    };
    Vector {
        x: axis(t.scale.x, t.offset.x),
        y: axis(t.scale.y, t.offset.y),
        z: axis(t.scale.z, t.offset.z),
    }
}

impl LasWriter {
    pub fn create(path: &Path, spec: &WriterSpec, compressed: bool) -> Result<Self, IoError> {
        let las_fail = |reason: &str| IoError::Las {
            path: path.to_path_buf(),
            reason: reason.into(),
        };
        let transform = match (spec.las_transform, &spec.bounds) {
            (Some(t), _) => t,
            (None, Some(b)) => {
                choose_las_transform(b).ok_or_else(|| las_fail("bounds are empty or not finite"))?
            }
            (None, None) => {
                return Err(las_fail(
                    "LAS output needs the points' bounds or a scale/offset transform",
                ))
            }
        };
        let valid = transform.scale.is_finite()
            && transform.scale.cmpgt(DVec3::ZERO).all()
            && transform.offset.is_finite();
        if !valid {
            return Err(las_fail("scale must be finite and positive, offset finite"));
        }
        let (number, gps_at, rgb_at) = point_format(spec.attributes);
        let mut fmt = Format::new(number).map_err(|e| las_error(path, e))?;
        let mut builder = Builder::from((1, 2));
        if spec.with_normals {
            fmt.extra_bytes = NORMAL_BYTES;
            builder.vlrs.push(normals_vlr());
        }
        builder.point_format = fmt;
        builder.point_format.is_compressed = compressed;
        builder.transforms = to_vector(&transform);
        builder.generating_software = "scanmesh".into();
        let header = builder.into_header().map_err(|e| las_error(path, e))?;
        let (atomic, out) = open_output(path)?;
        let abandoned = Arc::new(AtomicBool::new(false));
        let guarded = Guarded {
            out,
            abandoned: Arc::clone(&abandoned),
            pos: 0,
            len: 0,
        };
        let writer = Writer::new(guarded, header).map_err(|e| las_error(path, e))?;
        let data = PointDataBuilder::new()
            .with_format(fmt)
            .with_transforms(to_vector(&transform))
            .build();
        Ok(LasWriter {
            path: path.to_path_buf(),
            spec: spec.clone(),
            writer: Some(writer),
            atomic: Some(atomic),
            abandoned,
            transform,
            data,
            record_len: usize::from(fmt.len()),
            gps_at,
            rgb_at,
            count: 0,
        })
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
        reason: format!(
            "point {record} ({}, {}, {}) is outside the i32 range of scale {} offset {}",
            p.x, p.y, p.z, t.scale, t.offset
        ),
    })
}

impl PointWriter for LasWriter {
    fn write_chunk(&mut self, chunk: &PointChunk, flags: Option<&[u8]>) -> Result<(), IoError> {
        let c = check_chunk(&self.path, &self.spec, chunk, flags, self.count)?;
        let set = self.spec.attributes;
        let bytes = self.data.resize_for(chunk.len());
        for (i, (rec, p)) in bytes
            .chunks_exact_mut(self.record_len)
            .zip(&chunk.xyz)
            .enumerate()
        {
            let record = self.count + i as u64;
            let q = quantise(&self.transform, &self.path, *p, record)?;
            rec.fill(0);
            LittleEndian::write_i32_into(&q, &mut rec[..12]);
            rec[USER_DATA_AT] = c.flags.map_or(0, |f| f[i]);
            let a = chunk.attrs.get(i);
            let has = |x| set.contains(x);
            rec[RETURNS_AT] = returns_byte(has(Attribute::ReturnNumber).then_some(a.return_number));
            if has(Attribute::Intensity) {
                LittleEndian::write_u16(&mut rec[INTENSITY_AT..], a.intensity);
            }
            if a.classification > MAX_CLASS || a.return_number > MAX_RETURN {
                return Err(IoError::Las {
                    path: self.path.clone(),
                    reason: format!(
                        "point {record} has class {} and return number {}; LAS point formats 0-3 \
                         hold classes up to {MAX_CLASS}, LAS 1.2 return numbers up to {MAX_RETURN}",
                        a.classification, a.return_number
                    ),
                });
            }
            rec[CLASS_AT] = a.classification;
            if let Some(at) = self.gps_at {
                LittleEndian::write_f64(&mut rec[at..], a.gps_time);
            }
            if let Some(at) = self.rgb_at {
                LittleEndian::write_u16_into(&a.rgb, &mut rec[at..at + 6]);
            }
            if let Some(n) = c.normals {
                let at = self.record_len - usize::from(NORMAL_BYTES);
                LittleEndian::write_f32_into(&n[i].to_array(), &mut rec[at..]);
            }
        }
        let written = match &mut self.writer {
            Some(w) => w.write_points(&self.data),
            None => Ok(()),
        };
        written.map_err(|e| las_error(&self.path, e))?;
        self.count += chunk.len() as u64;
        Ok(())
    }

    fn finish(mut self: Box<Self>) -> Result<u64, IoError> {
        let path = self.path.clone();
        let (Some(mut writer), Some(atomic)) = (self.writer.take(), self.atomic.take()) else {
            return Err(IoError::Las {
                path,
                reason: "writer already finished".into(),
            });
        };
        if let Err(e) = writer.close() {
            self.abandoned.store(true, Ordering::Relaxed);
            // The las writer closes itself again on drop and panics when
            // that fails, as it would here (a header it cannot write): it
            // is leaked instead, once, on this error path.
            std::mem::forget(writer);
            return Err(las_error(&path, e));
        }
        let guarded = writer.into_inner().map_err(|e| las_error(&path, e))?;
        guarded
            .out
            .into_inner()
            .map_err(|e| IoError::os(&path, e.into_error()))?;
        atomic.commit()?;
        Ok(self.count)
    }
}

impl Drop for LasWriter {
    fn drop(&mut self) {
        // Unfinished: let the las writer's own drop-time close write nowhere.
        self.abandoned.store(true, Ordering::Relaxed);
    }
}
