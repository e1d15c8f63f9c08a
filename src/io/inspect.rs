//! `scanmesh info` for files: what the header says, plus the facts one
//! streaming pass gives (count, bounds, and the spacing measured in a few
//! exact neighbourhoods as the points stream past, whatever the file's
//! order: `spatial::patches`).

use super::{open_reader, IoError, LeftOut, PointChunk, ReadOptions, SourceInfo, DEFAULT_CHUNK};
use crate::geom::Aabb;
use crate::progress::Progress;
use crate::spatial::patches::SpacingPatches;
use std::path::Path;

/// What a pass over a whole input found (`scanmesh info`).
#[derive(Clone, Debug)]
pub struct Inspection {
    /// What the header declares.
    pub info: SourceInfo,
    /// Points read (after dropping skipped records).
    pub count: u64,
    /// Records dropped (non-finite or a cut last line, under
    /// [`InvalidPolicy::Skip`](super::InvalidPolicy::Skip); or flagged
    /// invalid by the file).
    pub skipped: u64,
    /// Records that hold no point to process (an organised cloud's pixels
    /// without a return) or that the read's selection left out.
    pub left_out: LeftOut,
    /// Bounding box of the points read.
    pub bounds: Aabb,
    /// Mean nearest-neighbour distance of the points read (exact
    /// duplicates left out), from exact neighbourhoods of a few of them;
    /// `None` with fewer than two distinct points.
    pub spacing: Option<f64>,
}

/// `read` is an [`InvalidPolicy`](super::InvalidPolicy) or [`ReadOptions`].
pub fn inspect(
    path: &Path,
    read: impl Into<ReadOptions>,
    progress: &dyn Progress,
) -> Result<Inspection, IoError> {
    let mut reader = open_reader(path, read)?;
    let info = reader.info().clone();
    let mut chunk = PointChunk::default();
    let mut bounds = Aabb::EMPTY;
    let mut count = 0;
    let mut spacing = SpacingPatches::new();
    progress.begin("inspect", info.declared_count.unwrap_or(0));
    while reader.read_chunk(&mut chunk, DEFAULT_CHUNK)? > 0 {
        chunk.xyz.iter().for_each(|p| bounds.add(*p));
        spacing.offer(&chunk.xyz);
        count += chunk.len() as u64;
        progress.advance(chunk.len() as u64);
    }
    progress.end();
    Ok(Inspection {
        info,
        count,
        skipped: reader.skipped(),
        left_out: reader.left_out(),
        bounds,
        spacing: spacing.estimate(),
    })
}

/// One scan of an E57, as `info` lists it: what the file declares and what
/// a pass over its records found.
#[derive(Clone, Debug)]
pub struct ScanInspection {
    /// What the file declares about the scan.
    pub scan: super::e57::ScanInfo,
    /// Points of the scan that were read.
    pub points: u64,
    /// Records flagged invalid by the file (or non-finite, under
    /// [`super::InvalidPolicy::Skip`]).
    pub skipped: u64,
    /// Bounding box of the scan's points read, in the world frame.
    pub bounds: Aabb,
}

/// An E57 inspected scan by scan, in one pass over the file (each scan's
/// section is read once); the whole file's figures are their sums, its
/// spacing that of the first scan with points.
pub fn inspect_scans(
    path: &Path,
    policy: super::InvalidPolicy,
    progress: &dyn Progress,
) -> Result<(Inspection, Vec<ScanInspection>), IoError> {
    let scans = super::e57::list_scans(path)?;
    let mut whole: Option<Inspection> = None;
    let mut out = Vec::with_capacity(scans.len());
    for scan in scans {
        let read = ReadOptions {
            policy,
            scans: Some(vec![scan.index]),
            ..ReadOptions::default()
        };
        let one = inspect(path, read, progress)?;
        out.push(ScanInspection {
            scan,
            points: one.count,
            skipped: one.skipped,
            bounds: one.bounds,
        });
        whole = Some(match whole {
            None => one,
            Some(mut w) => {
                w.count += one.count;
                w.skipped += one.skipped;
                w.left_out = w.left_out.plus(one.left_out);
                w.bounds = w.bounds.union(&one.bounds);
                w.spacing = w.spacing.or(one.spacing);
                w
            }
        });
    }
    let whole = match whole {
        Some(mut w) => {
            w.info.declared_count = Some(out.iter().map(|s| s.scan.records).sum());
            w
        }
        // No scan at all: the plain inspection reports the empty file.
        None => inspect(path, policy, progress)?,
    };
    Ok((whole, out))
}
