//! A LAS file around its point records: the header, the VLRs and the bytes
//! up to the points, and after them the EVLRs (LAS 1.4) or the waveform
//! packets (LAS 1.3, one record of the EVLR layout). A LAS output of a LAS
//! input is written from these ([`LasSource::frame`]): the input's version,
//! point format, scale, offset, global encoding, system identifier, every
//! VLR and EVLR byte for byte in the input's order, with only what
//! describes the new file changed: the counts, bounds and offsets, the
//! generating software, the LASzip VLR (it describes the compression) and
//! the Extra Bytes VLR (extended by the columns scanmesh appends). A COPC
//! input's info VLR and hierarchy EVLR are left out: they give the byte
//! offsets of the input's octree chunks, which the output does not have.
//!
//! Records are read from their headers' lengths, each checked against the
//! bytes there are before anything is allocated.

use super::{IoError, LasReason};
use byteorder::{LittleEndian, ReadBytesExt, WriteBytesExt};
use las::raw;
use las::Version;
use std::fs::File;
use std::io::{self, BufReader, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

/// Bytes of a VLR header, and of an EVLR header (its length is a u64).
pub(crate) const VLR_HEADER: usize = 54;
const EVLR_HEADER: u64 = 60;

/// A record's user id and record id.
pub(crate) type RecordId = (&'static str, u16);
/// LASzip's description of the compression (laz-rs, LASzip).
pub(crate) const LASZIP: RecordId = ("laszip encoded", 22204);
/// COPC's info VLR (copc.io, "COPC info VLR").
pub(crate) const COPC_INFO: RecordId = ("copc", 1);
/// COPC's hierarchy EVLR: byte offsets of the octree's chunks.
const COPC_HIERARCHY: RecordId = ("copc", 1000);
/// The Extra Bytes VLR (LAS 1.4 R15 sec. 2.5.3.2).
pub(crate) const EXTRA_BYTES: RecordId = ("LASF_Spec", 4);
/// User id of the GeoTIFF keys and WKT records.
const PROJECTION: &str = "LASF_Projection";

/// The `las` crate's error `e` about the file `path`, as an [`IoError`]
/// (every LAS reader and writer reports through this).
pub(crate) fn las_error(path: &Path, e: las::Error) -> IoError {
    match e {
        las::Error::Io(e) => IoError::os(path, e),
        e => IoError::Las {
            path: path.to_path_buf(),
            reason: Box::new(LasReason::Library(e)),
        },
    }
}

/// The identifying fields every VLR and EVLR header has, as the file holds
/// them (trailing bytes after a name's NUL included).
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct RecordHeader {
    reserved: u16,
    user_id: [u8; 16],
    record_id: u16,
    description: [u8; 32],
}

impl RecordHeader {
    /// A header for a record scanmesh writes.
    pub(crate) fn new(id: RecordId, description: &str) -> Self {
        let mut h = RecordHeader {
            reserved: 0,
            user_id: [0; 16],
            record_id: id.1,
            description: [0; 32],
        };
        let user = id.0.as_bytes();
        h.user_id[..user.len()].copy_from_slice(user);
        let d = description.as_bytes();
        let n = d.len().min(31);
        h.description[..n].copy_from_slice(&d[..n]);
        h
    }

    /// The user id up to its first NUL.
    fn user(&self) -> &[u8] {
        self.user_id.split(|&b| b == 0).next().unwrap_or(&[])
    }

    /// Whether this is the record `id`.
    pub(crate) fn is(&self, id: RecordId) -> bool {
        self.user() == id.0.as_bytes() && self.record_id == id.1
    }

    fn read(r: &mut impl Read, extended: bool) -> io::Result<(Self, u64)> {
        let reserved = r.read_u16::<LittleEndian>()?;
        let mut user_id = [0; 16];
        r.read_exact(&mut user_id)?;
        let record_id = r.read_u16::<LittleEndian>()?;
        let len = match extended {
            true => r.read_u64::<LittleEndian>()?,
            false => u64::from(r.read_u16::<LittleEndian>()?),
        };
        let mut description = [0; 32];
        r.read_exact(&mut description)?;
        let h = RecordHeader {
            reserved,
            user_id,
            record_id,
            description,
        };
        Ok((h, len))
    }

    fn write(&self, w: &mut impl Write, len: RecordLen) -> io::Result<()> {
        w.write_u16::<LittleEndian>(self.reserved)?;
        w.write_all(&self.user_id)?;
        w.write_u16::<LittleEndian>(self.record_id)?;
        match len {
            RecordLen::Vlr(n) => w.write_u16::<LittleEndian>(n)?,
            RecordLen::Evlr(n) => w.write_u64::<LittleEndian>(n)?,
        }
        w.write_all(&self.description)
    }
}

#[derive(Clone, Copy)]
enum RecordLen {
    Vlr(u16),
    Evlr(u64),
}

/// A variable length record, in memory (at most 64 KiB of data).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Vlr {
    pub(crate) header: RecordHeader,
    pub(crate) data: Vec<u8>,
}

impl Vlr {
    /// Bytes the record takes in the file.
    pub(crate) fn len(&self) -> usize {
        VLR_HEADER + self.data.len()
    }

    /// The record at the start of `bytes` and its length, if it fits.
    fn parse(bytes: &[u8]) -> Option<(Vlr, usize)> {
        let mut r = bytes;
        let (header, len) = RecordHeader::read(&mut r, false).ok()?;
        let data = r.get(..len as usize)?.to_vec();
        let whole = VLR_HEADER + data.len();
        Some((Vlr { header, data }, whole))
    }

    fn write(&self, w: &mut impl Write) -> io::Result<()> {
        // Lengths are checked where records are made (`las_extra`).
        let len = u16::try_from(self.data.len()).unwrap_or(u16::MAX);
        self.header.write(w, RecordLen::Vlr(len))?;
        w.write_all(&self.data)
    }
}

/// An extended variable length record: its header, and where its data is
/// (possibly gigabytes of waveforms: copied, never held).
#[derive(Clone, Debug)]
pub(crate) struct Evlr {
    header: RecordHeader,
    /// Offset of its header in the input file.
    at: u64,
    /// Bytes of data after the header.
    len: u64,
}

/// A file holding the input's bytes from input offset `start` on (the
/// input itself, or a store's copy of its tail).
#[derive(Clone, Debug)]
pub(crate) struct TailFile {
    pub(crate) path: PathBuf,
    /// Where input offset `start` is in this file.
    pub(crate) offset: u64,
    /// The input offset of the first EVLR (or waveform record).
    pub(crate) start: u64,
}

impl TailFile {
    fn position(&self, input_offset: u64) -> u64 {
        self.offset + (input_offset - self.start)
    }
}

/// What a LAS/LAZ input holds around its point records.
#[derive(Clone, Debug)]
pub struct LasSource {
    pub(crate) header: raw::Header,
    /// The input's bytes before its points, as read (what a store keeps).
    pub(crate) head: Vec<u8>,
    pub(crate) vlrs: Vec<Vlr>,
    /// Bytes between the last VLR and the points (LAS 1.0's 0xDDCC, ...).
    pub(crate) vlr_padding: Vec<u8>,
    pub(crate) evlrs: Vec<Evlr>,
    pub(crate) tail: Option<TailFile>,
}

fn bad(path: &Path, reason: String) -> IoError {
    IoError::BadHeader {
        path: path.to_path_buf(),
        reason,
    }
}

/// The input offset of the first record after the points: the first EVLR
/// (LAS 1.4) or the waveform packets (LAS 1.3), whichever comes first.
pub(crate) fn tail_start(h: &raw::Header) -> Option<u64> {
    let evlr = h
        .evlr
        .filter(|e| e.number_of_evlrs > 0)
        .map(|e| e.start_of_first_evlr);
    let waveform = h.start_of_waveform_data_packet_record.filter(|&w| w > 0);
    [evlr, waveform]
        .into_iter()
        .flatten()
        .filter(|&at| at >= u64::from(h.offset_to_point_data))
        .min()
}

impl LasSource {
    /// Reads what the LAS/LAZ file at `path` holds around its points.
    pub fn read(path: &Path) -> Result<Self, IoError> {
        let os = |e| IoError::os(path, e);
        let mut file = File::open(path).map_err(os)?;
        let len = file.metadata().map_err(os)?.len();
        let header =
            raw::Header::read_from(BufReader::new(&mut file)).map_err(|e| las_error(path, e))?;
        let head_len = u64::from(header.offset_to_point_data);
        if head_len > len || head_len < u64::from(header.header_size) {
            return Err(bad(
                path,
                format!(
                    "the points start at byte {head_len}, outside the header ({} bytes) and file ({len} bytes)",
                    header.header_size
                ),
            ));
        }
        let mut head = vec![0; head_len as usize];
        file.seek(SeekFrom::Start(0)).map_err(os)?;
        file.read_exact(&mut head).map_err(os)?;
        let tail = tail_start(&header).map(|start| TailFile {
            path: path.to_path_buf(),
            offset: start,
            start,
        });
        Self::parse(path, header, head, tail, len)
    }

    /// The parts a store kept: the input's bytes before its points
    /// (`head`) and from its first EVLR on (`tail`).
    pub(crate) fn from_parts(head_path: &Path, tail_path: &Path) -> Result<Self, IoError> {
        let head = std::fs::read(head_path).map_err(|e| IoError::os(head_path, e))?;
        let header = raw::Header::read_from(&head[..]).map_err(|e| las_error(head_path, e))?;
        let tail = tail_start(&header).map(|start| TailFile {
            path: tail_path.to_path_buf(),
            offset: 0,
            start,
        });
        let end = match &tail {
            Some(t) => {
                let len = std::fs::metadata(tail_path)
                    .map_err(|e| IoError::os(tail_path, e))?
                    .len();
                t.start + len
            }
            None => 0,
        };
        Self::parse(head_path, header, head, tail, end)
    }

    /// Splits `head` into its VLRs and padding and finds the EVLRs of
    /// `tail`, whose bytes end at input offset `end`.
    fn parse(
        path: &Path,
        header: raw::Header,
        head: Vec<u8>,
        tail: Option<TailFile>,
        end: u64,
    ) -> Result<Self, IoError> {
        let mut at = usize::from(header.header_size);
        let n = header.number_of_variable_length_records;
        let mut vlrs = Vec::new();
        for k in 0..n {
            let found = head.get(at..).and_then(Vlr::parse);
            let Some((vlr, len)) = found else {
                return Err(bad(
                    path,
                    format!("VLR {k} of {n} runs past the start of the points"),
                ));
            };
            vlrs.push(vlr);
            at += len;
        }
        let vlr_padding = head.get(at..).unwrap_or(&[]).to_vec();
        let evlrs = match &tail {
            Some(t) => read_evlrs(path, &header, t, end)?,
            None => Vec::new(),
        };
        Ok(LasSource {
            header,
            head,
            vlrs,
            vlr_padding,
            evlrs,
            tail,
        })
    }

    /// The LAS version, as (major, minor).
    pub fn version(&self) -> (u8, u8) {
        (self.header.version.major, self.header.version.minor)
    }

    /// The point data record format (0-10), without LAZ's compression bits.
    pub fn point_format(&self) -> u8 {
        self.header.point_data_record_format & 0x3f
    }

    /// Bytes of one point record, extra bytes included.
    pub fn record_len(&self) -> u16 {
        self.header.point_data_record_length
    }

    /// Number of VLRs (the LASzip VLR of a LAZ included).
    pub fn vlr_count(&self) -> usize {
        self.vlrs.len()
    }

    /// Number of EVLRs (a LAS 1.3 file's waveform packets count as one).
    pub fn evlr_count(&self) -> usize {
        self.evlrs.len()
    }

    /// Whether the file is a COPC (a COPC info VLR, user id "copc",
    /// record 1).
    pub fn is_copc(&self) -> bool {
        self.vlrs.iter().any(|v| v.header.is(COPC_INFO))
    }

    /// Whether the file carries a coordinate reference system (GeoTIFF
    /// keys or WKT, as a VLR or an EVLR).
    pub fn has_crs(&self) -> bool {
        let vlr = self.vlrs.iter().map(|v| &v.header);
        let evlr = self.evlrs.iter().map(|e| &e.header);
        vlr.chain(evlr).any(|h| h.user() == PROJECTION.as_bytes())
    }

    /// Each VLR's and then each EVLR's user id and record id, in the
    /// file's order.
    pub fn record_ids(&self) -> Vec<(String, u16)> {
        let vlr = self.vlrs.iter().map(|v| &v.header);
        let evlr = self.evlrs.iter().map(|e| &e.header);
        vlr.chain(evlr)
            .map(|h| (String::from_utf8_lossy(h.user()).into_owned(), h.record_id))
            .collect()
    }

    /// The input's bytes before its points.
    pub(crate) fn head(&self) -> &[u8] {
        &self.head
    }

    /// The Extra Bytes VLR, if the input has one among its VLRs.
    pub(crate) fn extra_bytes_vlr(&self) -> Option<&Vlr> {
        self.vlrs.iter().find(|v| v.header.is(EXTRA_BYTES))
    }

    /// Whether the Extra Bytes record is an EVLR (LAS 1.4 allows it).
    pub(crate) fn extra_bytes_in_evlrs(&self) -> bool {
        self.evlrs.iter().any(|e| e.header.is(EXTRA_BYTES))
    }

    /// The frame of a LAS output written as this input came: its
    /// records `record_len` bytes long, its Extra Bytes VLR `extra`
    /// (`None`: the input's, unchanged), LAZ when `laszip` (that VLR).
    pub(crate) fn frame(&self, record_len: u16, extra: Option<Vlr>, laszip: Option<Vlr>) -> Frame {
        let mut header = self.header.clone();
        header.generating_software = software();
        header.point_data_record_length = record_len;
        let format = self.point_format();
        header.point_data_record_format = format | if laszip.is_some() { 0x80 } else { 0 };
        let mut vlrs: Vec<Vlr> = Vec::with_capacity(self.vlrs.len() + 2);
        let mut extra = extra;
        for v in &self.vlrs {
            if v.header.is(LASZIP) || v.header.is(COPC_INFO) {
                continue;
            }
            match (v.header.is(EXTRA_BYTES), extra.take()) {
                (true, Some(e)) => vlrs.push(e),
                (_, e) => {
                    extra = e;
                    vlrs.push(v.clone());
                }
            }
        }
        vlrs.extend(extra);
        vlrs.extend(laszip);
        let evlrs: Vec<Evlr> = self
            .evlrs
            .iter()
            .filter(|e| !e.header.is(COPC_HIERARCHY))
            .cloned()
            .collect();
        let waveform = self
            .header
            .start_of_waveform_data_packet_record
            .and_then(|w| evlrs.iter().position(|e| e.at == w));
        // LAS 1.4 R15 sec. 2.4: the legacy counts are kept only by a
        // file of formats 0-5 that keeps them; it keeps them if it did.
        let legacy = format < 6
            && (self.header.version < Version::new(1, 4)
                || self.header.number_of_point_records > 0
                || self
                    .header
                    .large_file
                    .is_none_or(|l| l.number_of_point_records == 0));
        Frame {
            header,
            vlrs,
            vlr_padding: self.vlr_padding.clone(),
            evlrs,
            tail: self.tail.clone(),
            waveform,
            legacy,
        }
    }
}

/// The EVLRs of `tail`: the header's count of them from its first (LAS
/// 1.4), or the one waveform record (LAS 1.3); each must end by `end`.
fn read_evlrs(
    path: &Path,
    header: &raw::Header,
    tail: &TailFile,
    end: u64,
) -> Result<Vec<Evlr>, IoError> {
    let (mut at, n) = match header.evlr.filter(|e| e.number_of_evlrs > 0) {
        Some(e) => (e.start_of_first_evlr, e.number_of_evlrs),
        None => (tail.start, 1),
    };
    let os = |e| IoError::os(&tail.path, e);
    let mut file = BufReader::new(File::open(&tail.path).map_err(os)?);
    let mut evlrs = Vec::new();
    for k in 0..n {
        let past = |what: &str| {
            bad(
                path,
                format!("EVLR {k} of {n} ({what}) runs past the end of the file"),
            )
        };
        if at < tail.start || at.saturating_add(EVLR_HEADER) > end {
            return Err(past("its header"));
        }
        file.seek(SeekFrom::Start(tail.position(at))).map_err(os)?;
        let (h, len) = RecordHeader::read(&mut file, true).map_err(os)?;
        let next = (at + EVLR_HEADER).checked_add(len).filter(|&e| e <= end);
        let Some(next) = next else {
            return Err(past(&format!("{len} bytes of data")));
        };
        evlrs.push(Evlr { header: h, at, len });
        at = next;
    }
    Ok(evlrs)
}

/// "scanmesh" as the header's 32-byte generating software.
fn software() -> [u8; 32] {
    let mut s = [0; 32];
    s[..8].copy_from_slice(b"scanmesh");
    s
}

/// What a LAS output wrote, for its header.
#[derive(Clone, Debug)]
pub(crate) struct Stats {
    pub(crate) count: u64,
    /// Points by return number (0-15).
    pub(crate) by_return: [u64; 16],
    pub(crate) min: [i32; 3],
    pub(crate) max: [i32; 3],
}

impl Default for Stats {
    fn default() -> Self {
        Stats {
            count: 0,
            by_return: [0; 16],
            min: [i32::MAX; 3],
            max: [i32::MIN; 3],
        }
    }
}

impl Stats {
    /// Counts a record with integer coordinates `xyz` and return number
    /// `ret`.
    #[inline]
    pub(crate) fn add(&mut self, xyz: [i32; 3], ret: u8) {
        self.count += 1;
        self.by_return[usize::from(ret & 15)] += 1;
        for ((lo, hi), v) in self.min.iter_mut().zip(&mut self.max).zip(xyz) {
            *lo = (*lo).min(v);
            *hi = (*hi).max(v);
        }
    }
}

/// A LAS output's file-level parts: the header (counts, bounds and
/// offsets set when the points are written), the VLRs, and the EVLRs to
/// copy after the points.
#[derive(Clone, Debug)]
pub(crate) struct Frame {
    pub(crate) header: raw::Header,
    pub(crate) vlrs: Vec<Vlr>,
    pub(crate) vlr_padding: Vec<u8>,
    evlrs: Vec<Evlr>,
    tail: Option<TailFile>,
    /// The EVLR the header's waveform start points at.
    waveform: Option<usize>,
    /// Whether the legacy point counts are kept.
    legacy: bool,
}

impl Frame {
    /// A new file's frame (no input to follow): `version`, point format
    /// byte `format` (with LAZ's bit), records `record_len` bytes, these
    /// VLRs.
    pub(crate) fn new(version: Version, format: u8, record_len: u16, vlrs: Vec<Vlr>) -> Self {
        // Without LAZ's compression bits (0x80, 0x40).
        let extended = format & 0x3f >= 6;
        let (year, day) = today();
        let header = raw::Header {
            version,
            header_size: version.header_size(),
            // LAS 1.4 R15 sec. 2.4: formats 6-10 take a WKT CRS, if any.
            global_encoding: if extended { 16 } else { 0 },
            system_identifier: system(),
            generating_software: software(),
            file_creation_year: year,
            file_creation_day_of_year: day,
            point_data_record_format: format,
            point_data_record_length: record_len,
            ..Default::default()
        };
        Frame {
            header,
            vlrs,
            vlr_padding: Vec::new(),
            evlrs: Vec::new(),
            tail: None,
            waveform: None,
            legacy: !extended,
        }
    }

    /// Where the points start: after the header, the VLRs and the padding.
    pub(crate) fn offset_to_points(&self) -> u64 {
        let vlrs: usize = self.vlrs.iter().map(Vlr::len).sum();
        u64::from(self.header.header_size) + (vlrs + self.vlr_padding.len()) as u64
    }

    /// Writes the header, the VLRs and the padding (the header as it is
    /// now: a placeholder until [`Frame::finish`]).
    pub(crate) fn write_head(&mut self, w: &mut impl Write) -> Result<(), las::Error> {
        self.header.offset_to_point_data = u32::try_from(self.offset_to_points())
            .map_err(|_| las::Error::OffsetToPointDataTooLarge(self.offset_to_points() as usize))?;
        self.header.number_of_variable_length_records = self.vlrs.len() as u32;
        self.header.write_to(&mut *w)?;
        for v in &self.vlrs {
            v.write(w)?;
        }
        w.write_all(&self.vlr_padding)?;
        Ok(())
    }

    /// Copies the EVLRs to `w`, which is at input-independent offset
    /// `at`; returns the offset of each.
    pub(crate) fn write_evlrs(&self, w: &mut impl Write, mut at: u64) -> io::Result<Vec<u64>> {
        let Some(tail) = &self.tail else {
            return Ok(Vec::new());
        };
        let mut file = BufReader::new(File::open(&tail.path)?);
        let mut offsets = Vec::with_capacity(self.evlrs.len());
        for e in &self.evlrs {
            offsets.push(at);
            e.header.write(w, RecordLen::Evlr(e.len))?;
            file.seek(SeekFrom::Start(tail.position(e.at) + EVLR_HEADER))?;
            let copied = io::copy(&mut (&mut file).take(e.len), w)?;
            if copied != e.len {
                return Err(io::ErrorKind::UnexpectedEof.into());
            }
            at += EVLR_HEADER + e.len;
        }
        Ok(offsets)
    }

    /// Sets the header's counts, bounds and the offsets of the EVLRs
    /// written at `evlrs`.
    pub(crate) fn finish(&mut self, s: &Stats, evlrs: &[u64]) {
        let h = &mut self.header;
        let legacy = self.legacy && s.count <= u64::from(u32::MAX);
        let u32_of = |n: u64| u32::try_from(n).unwrap_or(0);
        h.number_of_point_records = if legacy { u32_of(s.count) } else { 0 };
        h.number_of_points_by_return = std::array::from_fn(|k| {
            if legacy {
                u32_of(s.by_return[k + 1])
            } else {
                0
            }
        });
        if h.version >= Version::new(1, 4) {
            h.large_file = Some(raw::header::LargeFile {
                number_of_point_records: s.count,
                number_of_points_by_return: std::array::from_fn(|k| s.by_return[k + 1]),
            });
            h.evlr = Some(raw::header::Evlr {
                start_of_first_evlr: evlrs.first().copied().unwrap_or(0),
                number_of_evlrs: evlrs.len() as u32,
            });
        }
        h.start_of_waveform_data_packet_record = self.waveform.and_then(|k| evlrs.get(k).copied());
        let coord = |a: usize, i: i32| {
            let (scale, offset) = match a {
                0 => (h.x_scale_factor, h.x_offset),
                1 => (h.y_scale_factor, h.y_offset),
                _ => (h.z_scale_factor, h.z_offset),
            };
            match s.count {
                0 => 0.0,
                _ => scale * f64::from(i) + offset,
            }
        };
        let (min, max) = (s.min, s.max);
        h.min_x = coord(0, min[0]);
        h.min_y = coord(1, min[1]);
        h.min_z = coord(2, min[2]);
        h.max_x = coord(0, max[0]);
        h.max_y = coord(1, max[1]);
        h.max_z = coord(2, max[2]);
    }
}

/// "OTHER" as a header's 32-byte system identifier (LAS 1.4 R15 table 2:
/// data not straight from a sensor).
fn system() -> [u8; 32] {
    let mut s = [0; 32];
    s[..5].copy_from_slice(b"OTHER");
    s
}

/// Today (UTC) as (year, day of the year from 1), for a new file's header.
fn today() -> (u16, u16) {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let days = (secs / 86_400) as i64;
    let (mut year, mut left) = (1970i64, days);
    loop {
        let leap = (year % 4 == 0 && year % 100 != 0) || year % 400 == 0;
        let len = if leap { 366 } else { 365 };
        if left < len {
            return (year as u16, left as u16 + 1);
        }
        left -= len;
        year += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_record_header_names_its_record() {
        let h = RecordHeader::new(EXTRA_BYTES, "Extra Bytes Record");
        assert!(h.is(EXTRA_BYTES) && !h.is(LASZIP));
        let vlr = Vlr {
            header: h,
            data: vec![1, 2, 3],
        };
        let mut bytes = Vec::new();
        vlr.write(&mut bytes).unwrap();
        assert_eq!(bytes.len(), vlr.len());
        let (back, len) = Vlr::parse(&bytes).unwrap();
        assert_eq!((back, len), (vlr, 57));
        assert!(Vlr::parse(&bytes[..56]).is_none());
    }

    #[test]
    fn today_is_a_day_of_a_year() {
        let (year, day) = today();
        assert!(year >= 2024 && (1..=366).contains(&day), "{year} {day}");
    }
}
