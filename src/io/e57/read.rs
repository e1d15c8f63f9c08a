//! The streaming E57 point reader: every selected scan in file order, each
//! point taken into the file's world frame by its scan's pose in f64.
//!
//! Records the file flags as not being points (`cartesianInvalidState` or
//! `sphericalInvalidState` 1, a direction only, or 2, no coordinate) are
//! skipped under every policy and counted ([`E57Reader::flagged`], part of
//! [`PointReader::skipped`]); nothing is made up for them. Spherical
//! records are converted to cartesian in the scan's frame first.
//!
//! Decoding runs on a thread of its own (as for LAS): the e57 crate's
//! point iterator borrows its file reader, so both live on the worker,
//! which sends blocks of [`BLOCK`] records through a channel of [`AHEAD`]:
//! memory is a few blocks whatever the file's size. The crate decodes one
//! data packet (at most 64 KiB) at a time.
//!
//! Intensity and colour are carried when every selected scan has them,
//! normalised by the scan's limits (the crate's default) and scaled to
//! 16 bits; a point whose own value is flagged invalid gets 0, the value
//! LAS and PLY would hold for "none".

use super::scan::{describe, ScanInfo, Transform};
use super::seekbuf::SeekBuf;
use crate::io::attributes::to_unsigned;
use crate::io::policy::Admitter;
use crate::io::{
    Attribute, AttributeSet, AttributeValues, E57Reason, E57Step, Format, IoError, PointChunk,
    PointReader, ReadOptions, ScanStation, SourceInfo,
};
use ::e57::{CartesianCoordinate, PointCloud};
use crossbeam::channel::{bounded, unbounded, Receiver, Sender};
use glam::{DVec3, Vec3};
use std::fs::File;
use std::path::{Path, PathBuf};
use std::thread::JoinHandle;

/// Records per block sent by the worker.
const BLOCK: usize = 1 << 15;
/// Blocks decoded ahead of the consumer.
const AHEAD: usize = 2;

type File57 = ::e57::E57Reader<SeekBuf<File>>;

/// A block of consecutive records of one scan: `first` is the file-wide
/// record number of `recs[0]`; `None` is a record flagged invalid;
/// `values` are the records' attributes.
#[derive(Default)]
struct Block {
    first: u64,
    recs: Vec<Option<DVec3>>,
    values: Vec<AttributeValues>,
}

/// A selected scan as the worker reads it.
struct Planned {
    cloud: PointCloud,
    index: usize,
    /// File-wide record number of the scan's first record.
    base: u64,
    transform: Transform,
}

/// A reader of an E57 file: the selected scans in file order, each point moved into the world frame by its scan's pose.
pub struct E57Reader {
    info: SourceInfo,
    scans: Vec<ScanInfo>,
    blocks: Receiver<Result<Block, IoError>>,
    recycle: Sender<Block>,
    worker: Option<JoinHandle<()>>,
    current: Block,
    pos: usize,
    admit: Admitter,
    /// Records of the selected scans, valid or not.
    declared: u64,
    consumed: u64,
    flagged: u64,
    /// The selected scans' record runs and scanner positions.
    stations: Vec<ScanStation>,
}

/// An e57 crate error as ours (its message already holds its source's).
pub(crate) fn e57_error(path: &Path, step: E57Step, error: ::e57::Error) -> IoError {
    IoError::E57 {
        path: path.to_path_buf(),
        reason: Box::new(E57Reason::Library { step, error }),
    }
}

/// Bytes of the binary header every E57 starts with.
const HEADER_BYTES: u64 = 48;

/// Opens `path` with the e57 crate and describes every scan.
pub(crate) fn open_file(path: &Path) -> Result<(File57, Vec<ScanInfo>), IoError> {
    let os = |e| IoError::os(path, e);
    let file = File::open(path).map_err(os)?;
    let len = file.metadata().map_err(os)?.len();
    if len < HEADER_BYTES {
        return Err(IoError::E57 {
            path: path.to_path_buf(),
            reason: Box::new(E57Reason::Truncated {
                bytes: len,
                header: HEADER_BYTES,
            }),
        });
    }
    let reader = ::e57::E57Reader::new(SeekBuf::new(file)).map_err(|e| {
        e57_error(
            path,
            E57Step::Named("cannot read the E57 header and XML"),
            e,
        )
    })?;
    let scans = reader
        .pointclouds()
        .iter()
        .enumerate()
        .map(|(i, pc)| describe(path, i, pc))
        .collect::<Result<Vec<_>, _>>()?;
    Ok((reader, scans))
}

/// Which scans to read: all, or the selection, each at most once and in
/// file order.
fn selected(
    path: &Path,
    scans: &[ScanInfo],
    pick: Option<&[usize]>,
) -> Result<Vec<usize>, IoError> {
    let Some(pick) = pick else {
        return Ok((0..scans.len()).collect());
    };
    if let Some(&bad) = pick.iter().find(|&&i| i >= scans.len()) {
        return Err(IoError::E57 {
            path: path.to_path_buf(),
            reason: Box::new(E57Reason::NoSuchScan {
                named: bad,
                scans: scans.len(),
            }),
        });
    }
    let mut out = pick.to_vec();
    out.sort_unstable();
    out.dedup();
    Ok(out)
}

impl E57Reader {
    pub(crate) fn open(path: &Path, read: &ReadOptions) -> Result<Self, IoError> {
        let (file, scans) = open_file(path)?;
        let picked = selected(path, &scans, read.scans.as_deref())?;
        let clouds = file.pointclouds();
        let mut plan = Vec::with_capacity(picked.len());
        let mut stations = Vec::with_capacity(picked.len());
        let mut declared = 0u64;
        let mut posed = true;
        for &i in &picked {
            let base = scans[..i]
                .iter()
                .map(|s| s.records)
                .fold(0u64, u64::saturating_add);
            declared = declared.saturating_add(scans[i].records);
            stations.push(ScanStation {
                first_record: base,
                records: scans[i].records,
                position: DVec3::from_array(scans[i].pose.translation),
            });
            // A scan without a pose has no known station (the Stanford
            // bunny of libE57Format's test data: a merged, all-round scan
            // whose "station" at the origin turned 88 % of its normals
            // in); with any such scan the file names none, rather than
            // orient some points by their station and the rest otherwise.
            posed &= scans[i].posed;
            plan.push(Planned {
                cloud: clouds[i].clone(),
                index: i,
                base,
                transform: scans[i].pose.transform(),
            });
        }
        if !posed {
            stations.clear();
        }
        let (block_tx, block_rx) = bounded(AHEAD);
        let (recycle_tx, recycle_rx) = unbounded();
        let owned = path.to_path_buf();
        let worker = std::thread::Builder::new()
            .name("e57-decode".into())
            .spawn(move || decode(owned, file, plan, block_tx, recycle_rx))
            .map_err(|e| IoError::os(path, e))?;
        let info = SourceInfo {
            path: path.to_path_buf(),
            format: Format::E57,
            gzip: false,
            declared_count: Some(declared),
            has_normals: false,
            attributes: common_attributes(&picked.iter().map(|&i| &scans[i]).collect::<Vec<_>>()),
            header_bounds: None,
            las_transform: None,
        };
        Ok(E57Reader {
            info,
            scans,
            blocks: block_rx,
            recycle: recycle_tx,
            worker: Some(worker),
            current: Block::default(),
            pos: 0,
            admit: Admitter::new(path.to_path_buf(), read.policy),
            declared,
            consumed: 0,
            flagged: 0,
            stations,
        })
    }

    /// Every scan of the file (selected or not).
    pub fn scans(&self) -> &[ScanInfo] {
        &self.scans
    }

    /// Records skipped so far because the file flags them as no point.
    pub fn flagged(&self) -> u64 {
        self.flagged
    }

    /// Makes `current.recs[pos..]` non-empty (the next block from the worker).
    fn refill(&mut self) -> Result<(), IoError> {
        let block = self
            .blocks
            .recv()
            .map_err(|_| worker_died(&self.info.path))??;
        let old = std::mem::replace(&mut self.current, block);
        // The worker may be gone already; then the buffer is simply dropped.
        let _ = self.recycle.send(old);
        self.pos = 0;
        match self.current.recs.is_empty() {
            true => Err(worker_died(&self.info.path)),
            false => Ok(()),
        }
    }
}

fn worker_died(path: &Path) -> IoError {
    IoError::E57 {
        path: path.to_path_buf(),
        reason: Box::new(E57Reason::DecoderStopped),
    }
}

/// Worker: decodes the planned scans in order until the end, an error, or
/// until the consumer hangs up.
fn decode(
    path: PathBuf,
    mut file: File57,
    plan: Vec<Planned>,
    blocks: Sender<Result<Block, IoError>>,
    recycle: Receiver<Block>,
) {
    for scan in plan {
        if let Err(e) = decode_scan(&path, &mut file, &scan, &blocks, &recycle) {
            let _ = blocks.send(Err(e));
            return;
        }
    }
}

/// Sends one scan's records; `Ok` also when the consumer has hung up.
fn decode_scan(
    path: &Path,
    file: &mut File57,
    scan: &Planned,
    blocks: &Sender<Result<Block, IoError>>,
    recycle: &Receiver<Block>,
) -> Result<(), IoError> {
    let total = scan.cloud.records;
    if total == 0 {
        return Ok(());
    }
    let what = |record: u64| E57Step::Record {
        scan: scan.index,
        record,
        total,
    };
    let mut points = file
        .pointcloud_simple(&scan.cloud)
        .map_err(|e| e57_error(path, what(0), e))?;
    // Coordinates only, untouched: the pose is applied here, normalised.
    points.apply_pose(false);
    points.spherical_to_cartesian(true);
    points.intensity_to_color(false);
    points.normalize_color(true);
    points.normalize_intensity(true);
    let mut done = 0u64;
    while done < total {
        let mut block = recycle.try_recv().unwrap_or_default();
        block.recs.clear();
        block.values.clear();
        let want = (total - done).min(BLOCK as u64) as usize;
        for _ in 0..want {
            let p = match points.next() {
                Some(Ok(p)) => p,
                Some(Err(e)) => return Err(e57_error(path, what(done), e)),
                None => return Err(e57_error(path, what(done), ended_early())),
            };
            block.values.push(values_of(&p));
            block.recs.push(match p.cartesian {
                CartesianCoordinate::Valid { x, y, z } => {
                    Some(scan.transform.apply(DVec3::new(x, y, z)))
                }
                // A direction without range, or no coordinate at all.
                CartesianCoordinate::Direction { .. } | CartesianCoordinate::Invalid => None,
            });
            done += 1;
        }
        block.first = scan.base.saturating_add(done - want as u64);
        if blocks.send(Ok(block)).is_err() {
            return Ok(());
        }
    }
    Ok(())
}

/// A point's intensity and colour, from the crate's 0-1 values.
fn values_of(p: &::e57::Point) -> AttributeValues {
    let scale = |v: f32| to_unsigned(f64::from(v) * 65535.0, u16::MAX);
    AttributeValues {
        intensity: p.intensity.map_or(0, scale),
        rgb: p
            .color
            .as_ref()
            .map_or([0; 3], |c| [c.red, c.green, c.blue].map(scale)),
        ..AttributeValues::default()
    }
}

/// The attributes every one of `scans` carries.
fn common_attributes(scans: &[&ScanInfo]) -> AttributeSet {
    let all = |name: &str| scans.iter().all(|s| s.attributes.contains(&name));
    let mut set = AttributeSet::EMPTY;
    if all("intensity") {
        set = set.with(Attribute::Intensity);
    }
    if all("color") {
        set = set.with(Attribute::Rgb);
    }
    set
}

fn ended_early() -> ::e57::Error {
    ::e57::Error::Read {
        desc: "the point data ended before the declared record count".into(),
        source: None,
    }
}

impl PointReader for E57Reader {
    fn info(&self) -> &SourceInfo {
        &self.info
    }

    fn stations(&self) -> Vec<ScanStation> {
        self.stations.clone()
    }

    /// `max` of 0 is taken as 1, since 0 points read means end of input.
    fn read_chunk(&mut self, chunk: &mut PointChunk, max: usize) -> Result<usize, IoError> {
        let max = max.max(1);
        let first = self.current.first + self.pos as u64;
        self.admit.begin(chunk, first, &self.info);
        while chunk.len() < max && self.consumed < self.declared {
            if self.pos == self.current.recs.len() {
                self.refill()?;
                self.admit.jump(chunk, self.current.first);
            }
            let block = &self.current;
            let take = (max - chunk.len()).min(block.recs.len() - self.pos);
            for (k, rec) in block.recs[self.pos..self.pos + take].iter().enumerate() {
                let record = block.first + (self.pos + k) as u64;
                match rec {
                    Some(p) => {
                        let a = &block.values[self.pos + k];
                        self.admit.push_with(chunk, record, *p, Vec3::ZERO, a)?
                    }
                    None => {
                        self.admit.pass(chunk);
                        self.flagged += 1;
                    }
                }
            }
            self.pos += take;
            self.consumed += take as u64;
        }
        Ok(self.admit.end(chunk))
    }

    fn skipped(&self) -> u64 {
        self.admit.skipped() + self.flagged
    }
}

impl Drop for E57Reader {
    fn drop(&mut self) {
        // Hang up first so a worker blocked on a full channel wakes and ends.
        let (_, dead) = bounded(0);
        drop(std::mem::replace(&mut self.blocks, dead));
        if let Some(w) = self.worker.take() {
            let _ = w.join();
        }
    }
}
