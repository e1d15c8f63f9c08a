//! LAS/LAZ point reader (ASPRS LAS 1.0-1.4, LAZ via laz-rs), over the `las`
//! crate: points are decoded block by block into one reused
//! [`las::PointData`], never all at once; coordinates come out scaled, f64.
//!
//! Decoding runs on a thread of its own, because `las::Reader` is not `Send`
//! (its backend is a `Box<dyn ReadPoints>` without a `Send` bound) while a
//! [`PointReader`] must be. A channel of `AHEAD` blocks keeps memory flat
//! and lets LAZ decompression overlap with the consumer.
//!
//! For uncompressed LAS the file length is checked against the declared
//! count at open, so a short file fails before any point is read, and so
//! is what follows the point records: bytes there that are not zero and
//! not the extended VLRs (LAS 1.4, from the header's start of the first
//! EVLR) or the waveform packets (LAS 1.3) are more records than declared,
//! or garbage ([`IoError::TrailingData`]). LAZ point data is followed by
//! its chunk table, so its bytes say nothing; the chunk table's point
//! counts do, and a LAZ whose chunks hold more points than the header
//! declares is refused the same way.

use super::las_file::las_error;
use super::policy::Admitter;
use super::source::BUF_CAPACITY;
use super::{
    Attribute, AttributeSet, Attributes, Format, InvalidPolicy, IoError, LasReason, LasTransform,
    PointChunk, PointReader, SourceInfo, Trailing,
};
use crate::geom::Aabb;
use byteorder::{ByteOrder, LittleEndian};
use crossbeam::channel::{bounded, unbounded, Receiver, Sender};
use glam::{DVec3, Vec3};
use las::{PointDataBuilder, Reader};
use std::fs::File;
use std::io::{BufReader, Seek, SeekFrom};
use std::path::{Path, PathBuf};
use std::thread::JoinHandle;

/// Points decoded per `las` call (about 1-2 MiB of raw records).
const BLOCK_POINTS: u64 = 1 << 16;
/// Blocks decoded ahead of the consumer.
const AHEAD: usize = 2;

/// Decoded points of one block, their normals (when the file has them in
/// its extra bytes) and their attributes.
#[derive(Default)]
struct Decoded {
    xyz: Vec<DVec3>,
    normals: Vec<Vec3>,
    attrs: Attributes,
    /// Each point's number of returns (for a selection of last returns).
    returns: Vec<u8>,
    /// The block's records as the file holds them (decompressed).
    records: Vec<u8>,
}

type Block = Result<Decoded, IoError>;

pub struct LasReader {
    info: SourceInfo,
    blocks: Receiver<Block>,
    recycle: Sender<Decoded>,
    worker: Option<JoinHandle<()>>,
    current: Decoded,
    pos: usize,
    admit: Admitter,
    declared: u64,
    next: u64,
    /// Bytes of one point record.
    record_len: usize,
}

/// The header's box, when it is one (finite, `min <= max`).
fn header_bounds(b: &las::Bounds) -> Option<Aabb> {
    let a = Aabb::new(
        DVec3::new(b.min.x, b.min.y, b.min.z),
        DVec3::new(b.max.x, b.max.y, b.max.z),
    );
    (a.min.is_finite() && a.max.is_finite() && !a.is_empty()).then_some(a)
}

/// Opens the file with `las` and checks its length; runs on the worker.
fn open_las(path: &Path) -> Result<(Reader, SourceInfo), IoError> {
    let os = |e| IoError::os(path, e);
    let mut file = File::open(path).map_err(os)?;
    let file_len = file.metadata().map_err(os)?.len();
    let raw =
        las::raw::Header::read_from(BufReader::new(&mut file)).map_err(|e| las_error(path, e))?;
    file.seek(SeekFrom::Start(0)).map_err(os)?;
    // `las` works out where the points end without checked arithmetic (a
    // panic with overflow checks, a wrapped offset without): a count whose
    // records no file could hold is refused first.
    let start = u64::from(raw.offset_to_point_data);
    let record = u64::from(raw.point_data_record_length);
    let count = raw_count(&raw);
    if count
        .checked_mul(record)
        .and_then(|b| b.checked_add(start))
        .is_none()
    {
        let found = file_len.saturating_sub(start) / record.max(1);
        return Err(truncated(path, count, found));
    }
    let reader = match Reader::new(BufReader::with_capacity(BUF_CAPACITY, file)) {
        Ok(r) => r,
        Err(e) if ends_early(&e) => return Err(truncated(path, raw_count(&raw), 0)),
        Err(e) => return Err(las_error(path, e)),
    };
    let header = reader.header();
    let declared = header.number_of_points();
    let compressed = header.point_format().is_compressed;
    if !compressed {
        let record = u64::from(header.point_format().len()).max(1);
        let found = file_len.saturating_sub(start) / record;
        if found < declared {
            return Err(IoError::Truncated {
                path: path.to_path_buf(),
                declared,
                found,
            });
        }
        check_las_tail(
            path,
            &raw,
            start + declared * record,
            file_len,
            declared,
            record,
        )?;
    } else {
        check_laz_chunks(path, header, u64::from(raw.offset_to_point_data), declared)?;
    }
    let t = header.transforms();
    let format = header.point_format();
    // Every LAS record has intensity, return number and classification.
    let mut attributes = AttributeSet::of(&[
        Attribute::Intensity,
        Attribute::Classification,
        Attribute::ReturnNumber,
    ]);
    if format.has_gps_time {
        attributes = attributes.with(Attribute::GpsTime);
    }
    if format.has_color {
        attributes = attributes.with(Attribute::Rgb);
    }
    let info = SourceInfo {
        path: path.to_path_buf(),
        format: if compressed { Format::Laz } else { Format::Las },
        gzip: false,
        declared_count: Some(declared),
        has_normals: crate::io::las_extra::find_normals(header).is_some(),
        attributes,
        header_bounds: header_bounds(&header.bounds()),
        las_transform: Some(LasTransform {
            scale: DVec3::new(t.x.scale, t.y.scale, t.z.scale),
            offset: DVec3::new(t.x.offset, t.y.offset, t.z.offset),
        }),
    };
    Ok((reader, info))
}

/// Where the point records of an uncompressed LAS may end at the latest:
/// the start of the extended VLRs (LAS 1.4) or of the waveform packets
/// (LAS 1.3) when they follow the points, else the end of the file.
fn end_of_point_region(raw: &las::raw::Header, points_end: u64, file_len: u64) -> u64 {
    let evlr = raw
        .evlr
        .as_ref()
        .filter(|e| e.number_of_evlrs > 0)
        .map(|e| e.start_of_first_evlr);
    let waveform = raw.start_of_waveform_data_packet_record.filter(|&w| w > 0);
    [evlr, waveform]
        .into_iter()
        .flatten()
        .filter(|&at| at >= points_end)
        .fold(file_len, u64::min)
}

/// Refuses bytes after the declared point records of an uncompressed LAS
/// (up to its EVLRs or waveform packets) unless they are all zero.
fn check_las_tail(
    path: &Path,
    raw: &las::raw::Header,
    points_end: u64,
    file_len: u64,
    declared: u64,
    record: u64,
) -> Result<(), IoError> {
    let stop = end_of_point_region(raw, points_end, file_len);
    if stop <= points_end {
        return Ok(());
    }
    let os = |e| IoError::os(path, e);
    let mut file = File::open(path).map_err(os)?;
    file.seek(SeekFrom::Start(points_end)).map_err(os)?;
    let mut tail = std::io::Read::take(BufReader::new(file), stop - points_end);
    match crate::io::source::binary_tail(&mut tail).map_err(os)? {
        None => Ok(()),
        Some(t) => Err(IoError::TrailingData {
            path: path.to_path_buf(),
            declared,
            extra_bytes: Some(t.bytes),
            found: t.found(Some(record)),
        }),
    }
}

/// Refuses a LAZ whose chunk table lists more points than the header
/// declares. A table that cannot be read is left to the decoder (LAZ
/// allows a missing one); fixed-size chunks say only how many there are,
/// so points past the count inside the last chunk go unseen, but a chunk
/// more than the count needs does not (laz-rs writes one empty chunk for
/// no points, so one chunk is always allowed).
fn check_laz_chunks(
    path: &Path,
    header: &las::Header,
    points_start: u64,
    declared: u64,
) -> Result<(), IoError> {
    let Ok(vlr) = header.laz_vlr() else {
        return Ok(());
    };
    let table = File::open(path).and_then(|mut f| {
        f.seek(SeekFrom::Start(points_start))?;
        Ok(laz::laszip::ChunkTable::read_from(BufReader::new(f), &vlr))
    });
    let Ok(Ok(table)) = table else {
        return Ok(());
    };
    let chunks = table.as_ref();
    let found = if vlr.uses_variable_size_chunks() {
        let listed: u64 = chunks.iter().map(|c| c.point_count).sum();
        (listed > declared).then_some(Trailing::ChunkPoints { listed })
    } else {
        let size = u64::from(vlr.chunk_size()).max(1);
        let needed = declared.div_ceil(size).max(1);
        (chunks.len() as u64 > needed).then_some(Trailing::Chunks {
            listed: chunks.len(),
            size,
            needed,
        })
    };
    match found {
        None => Ok(()),
        Some(found) => Err(IoError::TrailingData {
            path: path.to_path_buf(),
            declared,
            extra_bytes: None,
            found,
        }),
    }
}

/// Worker: decodes blocks until the declared count, an error, or until the
/// consumer hangs up.
fn decode_blocks(
    path: PathBuf,
    mut reader: Reader,
    set: AttributeSet,
    blocks: Sender<Block>,
    recycle: Receiver<Decoded>,
) {
    let declared = reader.header().number_of_points();
    let format = reader.header().point_format();
    // Normal offsets within a record: after the standard fields.
    let normals = crate::io::las_extra::find_normals(reader.header()).map(|n| {
        let base = usize::from(format.len() - format.extra_bytes);
        n.map(|at| base + at)
    });
    let mut data = PointDataBuilder::new().for_header(reader.header()).build();
    let mut done = 0u64;
    while done < declared {
        let n = (declared - done).min(BLOCK_POINTS);
        let block = match reader.fill_points(n, &mut data) {
            Ok(got) if got == n => {
                let mut d = recycle.try_recv().unwrap_or_default();
                d.xyz.clear();
                let (x, y, z) = (data.x(), data.y(), data.z());
                d.xyz
                    .extend(x.zip(y).zip(z).map(|((x, y), z)| DVec3::new(x, y, z)));
                decode_attributes(&data, set, &mut d.attrs);
                d.returns.clear();
                d.returns.extend(data.number_of_returns());
                d.records.clear();
                d.records.extend_from_slice(data.raw_bytes());
                d.normals.clear();
                if let Some(at) = normals {
                    let records = data.raw_bytes().chunks_exact(data.record_len());
                    d.normals
                        .extend(records.map(|r| {
                            Vec3::from_array(at.map(|o| LittleEndian::read_f32(&r[o..])))
                        }));
                }
                Ok(d)
            }
            Ok(got) => Err(truncated(&path, declared, done + got)),
            Err(e) if ends_early(&e) => Err(truncated(&path, declared, done)),
            Err(e) => Err(las_error(&path, e)),
        };
        let failed = block.is_err();
        done += n;
        if blocks.send(block).is_err() || failed {
            return;
        }
    }
}

/// The attribute columns of a decoded block.
fn decode_attributes(data: &las::PointData, set: AttributeSet, out: &mut Attributes) {
    out.reset(set);
    out.intensity.extend(data.intensity());
    out.classification.extend(data.classification());
    out.return_number.extend(data.return_number());
    if let Some(t) = data.gps_time() {
        out.gps_time.extend(t);
    }
    if let Some(c) = data.rgb() {
        out.rgb.extend(c.map(|(r, g, b)| [r, g, b]));
    }
}

/// True when the error comes from the data ending early (LAZ wraps the
/// `io::Error` in its own error type).
fn ends_early(e: &las::Error) -> bool {
    let io = match e {
        las::Error::Io(io) => io,
        las::Error::LasZipError(laz::LasZipError::IoError(io)) => io,
        _ => return false,
    };
    io.kind() == std::io::ErrorKind::UnexpectedEof
}

/// Point count of a raw header, as `las` takes it: the legacy 32-bit count
/// unless it is 0, then LAS 1.4's 64-bit one (LAS 1.4 R15 asks readers to
/// prefer a non-zero legacy count).
fn raw_count(raw: &las::raw::Header) -> u64 {
    match (raw.number_of_point_records, &raw.large_file) {
        (0, Some(l)) => l.number_of_point_records,
        (legacy, _) => u64::from(legacy),
    }
}

fn truncated(path: &Path, declared: u64, found: u64) -> IoError {
    IoError::Truncated {
        path: path.to_path_buf(),
        declared,
        found,
    }
}

impl LasReader {
    pub(crate) fn open(path: &Path, policy: InvalidPolicy) -> Result<Self, IoError> {
        let (info_tx, info_rx) = bounded::<Result<(SourceInfo, u16), IoError>>(1);
        let (block_tx, block_rx) = bounded::<Block>(AHEAD);
        let (recycle_tx, recycle_rx) = unbounded::<Decoded>();
        let owned = path.to_path_buf();
        let worker = std::thread::Builder::new()
            .name("las-decode".into())
            .spawn(move || match open_las(&owned) {
                Err(e) => {
                    let _ = info_tx.send(Err(e));
                }
                Ok((reader, info)) => {
                    let set = info.attributes;
                    let record_len = reader.header().point_format().len();
                    if info_tx.send(Ok((info, record_len))).is_ok() {
                        decode_blocks(owned, reader, set, block_tx, recycle_rx);
                    }
                }
            })
            .map_err(|e| IoError::os(path, e))?;
        let (info, record_len) = match info_rx.recv() {
            Ok(Ok(info)) => info,
            // The las crate reports a record that runs past the file as the
            // points ending early; the frame's own reading names the record.
            Ok(Err(e)) => return Err(super::LasSource::read(path).err().unwrap_or(e)),
            Err(_) => return Err(worker_died(path)),
        };
        Ok(LasReader {
            record_len: usize::from(record_len),
            declared: info.declared_count.unwrap_or(0),
            info,
            blocks: block_rx,
            recycle: recycle_tx,
            worker: Some(worker),
            current: Decoded::default(),
            pos: 0,
            admit: Admitter::new(path.to_path_buf(), policy),
            next: 0,
        })
    }

    /// Makes `current[pos..]` non-empty (the next block from the worker).
    fn refill(&mut self) -> Result<(), IoError> {
        let block = self
            .blocks
            .recv()
            .map_err(|_| worker_died(&self.info.path))??;
        let old = std::mem::replace(&mut self.current, block);
        // The worker may be gone already; then the buffer is simply dropped.
        let _ = self.recycle.send(old);
        self.pos = 0;
        match self.current.xyz.is_empty() {
            true => Err(worker_died(&self.info.path)),
            false => Ok(()),
        }
    }
}

fn worker_died(path: &Path) -> IoError {
    IoError::Las {
        path: path.to_path_buf(),
        reason: Box::new(LasReason::DecoderStopped),
    }
}

impl PointReader for LasReader {
    fn info(&self) -> &SourceInfo {
        &self.info
    }

    /// `max` of 0 is taken as 1, since 0 points read means end of input.
    fn read_chunk(&mut self, chunk: &mut PointChunk, max: usize) -> Result<usize, IoError> {
        let max = max.max(1);
        self.admit.begin(chunk, self.next, &self.info);
        chunk.attrs.las.record_len = self.record_len;
        let len = self.record_len;
        while chunk.len() < max && self.next < self.declared {
            if self.pos == self.current.xyz.len() {
                self.refill()?;
            }
            let take = (max - chunk.len()).min(self.current.xyz.len() - self.pos);
            for k in self.pos..self.pos + take {
                let (p, a) = (self.current.xyz[k], self.current.attrs.get(k));
                let n = self.current.normals.get(k).copied().unwrap_or(Vec3::ZERO);
                let before = chunk.len();
                self.admit.push_with(chunk, self.next, p, n, &a)?;
                if chunk.number_of_returns.len() < chunk.len() {
                    chunk.number_of_returns.push(self.current.returns[k]);
                }
                // The record goes with its point, whether it was taken.
                if chunk.len() > before {
                    let record = &self.current.records[k * len..(k + 1) * len];
                    chunk.attrs.las.bytes.extend_from_slice(record);
                }
                self.next += 1;
            }
            self.pos += take;
        }
        Ok(self.admit.end(chunk))
    }

    fn skipped(&self) -> u64 {
        self.admit.skipped()
    }
}

impl Drop for LasReader {
    fn drop(&mut self) {
        // Hang up first so a worker blocked on a full channel wakes and ends.
        let (_, dead) = bounded(0);
        drop(std::mem::replace(&mut self.blocks, dead));
        if let Some(w) = self.worker.take() {
            let _ = w.join();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points_may_be_followed_by_evlrs_or_waveforms_only() {
        let mut raw = las::raw::Header::default();
        // No EVLRs: the points run to the end of the file.
        assert_eq!(end_of_point_region(&raw, 1000, 1500), 1500);
        // LAS 1.4 EVLRs after the points: bytes from their start are theirs.
        raw.evlr = Some(las::raw::header::Evlr {
            start_of_first_evlr: 1200,
            number_of_evlrs: 1,
        });
        assert_eq!(end_of_point_region(&raw, 1000, 1500), 1200);
        // A start before the end of the points, or no EVLR, says nothing.
        raw.evlr = Some(las::raw::header::Evlr {
            start_of_first_evlr: 900,
            number_of_evlrs: 1,
        });
        assert_eq!(end_of_point_region(&raw, 1000, 1500), 1500);
        raw.evlr = Some(las::raw::header::Evlr {
            start_of_first_evlr: 1000,
            number_of_evlrs: 0,
        });
        assert_eq!(end_of_point_region(&raw, 1000, 1500), 1500);
        // LAS 1.3 waveform packets after the points.
        raw.start_of_waveform_data_packet_record = Some(1000);
        assert_eq!(end_of_point_region(&raw, 1000, 1500), 1000);
    }

    #[test]
    fn a_count_no_file_can_hold_is_truncated_not_a_panic() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("huge.las");
        let raw = las::raw::Header {
            version: las::Version::new(1, 4),
            header_size: 375,
            offset_to_point_data: 375,
            point_data_record_length: 20,
            large_file: Some(las::raw::header::LargeFile {
                number_of_point_records: u64::MAX / 4,
                number_of_points_by_return: [0; 15],
            }),
            evlr: Some(Default::default()),
            ..Default::default()
        };
        let mut bytes = Vec::new();
        raw.write_to(&mut bytes).unwrap();
        bytes.resize(375 + 40, 7);
        std::fs::write(&path, bytes).unwrap();
        match LasReader::open(&path, InvalidPolicy::Reject) {
            Err(IoError::Truncated {
                declared, found: 2, ..
            }) => assert_eq!(declared, u64::MAX / 4),
            Err(e) => panic!("{e:?}"),
            Ok(_) => panic!("opened"),
        }
    }
}
