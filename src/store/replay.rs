//! The points of the input, read again: the store build reads its input
//! three times (bounds, histogram, scatter) but may only parse it once when
//! it is text, compressed or a stream. The first pass then spills the
//! points (f64, 24 bytes each) to a scratch file that the later passes read;
//! an input its reader can reopen as cheaply (an uncompressed binary file
//! of fixed-size records, [`PointReader::reopen`]) is read again instead,
//! which saves writing and reading back a copy as large as the input
//! (2.4 GB at 100M points).

use super::attributes::AttributeSink;
use super::StoreError;
use crate::geom::Aabb;
use crate::io::{IoError, PointChunk, PointReader, DEFAULT_CHUNK};
use crate::progress::Progress;
use crossbeam::channel::{Receiver, Sender};
use glam::DVec3;
use std::fs::File;
use std::io::{BufReader, BufWriter, Read, Write};
use std::path::{Path, PathBuf};
use std::time::SystemTime;

/// Point ids are u32 in the orientation pass's union-find.
pub const MAX_POINTS: u64 = u32::MAX as u64 - 1;

/// Where the later passes find the points.
pub(super) enum Replay {
    /// A scratch copy of the valid points.
    Spill(PathBuf),
    /// The input itself, as long as its size and modification time are
    /// those it had when first read.
    Input(Option<(u64, SystemTime)>),
}

/// Reads every point of `reader` once: counts them, bounds them and, unless
/// the input can be reopened, spills them to `spill`.
pub(super) fn first_pass(
    reader: &mut dyn PointReader,
    spill: &Path,
    attributes: &mut AttributeSink,
    progress: &dyn Progress,
) -> Result<(u64, Aabb, Replay), StoreError> {
    let reopens = matches!(reader.reopen(), Some(Ok(_)));
    let stamp = reopens.then(|| stamp(&reader.info().path)).flatten();
    let mut out = match reopens {
        true => None,
        false => {
            let file = File::create(spill).map_err(|e| StoreError::os(spill, e))?;
            Some(BufWriter::with_capacity(1 << 20, file))
        }
    };
    let mut bounds = Aabb::EMPTY;
    let mut count = 0u64;
    progress.begin("read", reader.info().declared_count.unwrap_or(0));
    let path = reader.info().path.clone();
    read_ahead(reader, |chunk| {
        for p in &chunk.xyz {
            bounds.add(*p);
        }
        if let Some(out) = &mut out {
            write_points(out, &chunk.xyz).map_err(|e| StoreError::os(spill, e))?;
        }
        attributes.write(chunk)?;
        count += chunk.len() as u64;
        if count > MAX_POINTS {
            return Err(StoreError::TooMany {
                path: path.clone(),
                count,
                max: MAX_POINTS,
            });
        }
        progress.advance(chunk.len() as u64);
        Ok(())
    })?;
    if let Some(out) = &mut out {
        out.flush().map_err(|e| StoreError::os(spill, e))?;
    }
    progress.end();
    let replay = match out {
        Some(_) => Replay::Spill(spill.to_path_buf()),
        None => Replay::Input(stamp),
    };
    Ok((count, bounds, replay))
}

fn write_points(out: &mut impl Write, pts: &[DVec3]) -> std::io::Result<()> {
    for p in pts {
        for v in p.to_array() {
            out.write_all(&v.to_le_bytes())?;
        }
    }
    Ok(())
}

/// Calls `f` on each chunk of `reader` in order while the next chunk is
/// decoded on another thread: decoding is half the cost of a pass over a
/// binary file, and the other core is idle during ingest.
fn read_ahead(
    reader: &mut dyn PointReader,
    mut f: impl FnMut(&PointChunk) -> Result<(), StoreError>,
) -> Result<(), StoreError> {
    // Two chunks circulate: one decoded while the other is used.
    let (full_tx, full_rx) = crossbeam::channel::bounded::<Result<PointChunk, IoError>>(2);
    let (empty_tx, empty_rx) = crossbeam::channel::bounded::<PointChunk>(2);
    for _ in 0..2 {
        let _ = empty_tx.send(PointChunk::default());
    }
    std::thread::scope(|s| {
        s.spawn(move || {
            // Ends when the consumer hangs up (it returned early) or the
            // input does.
            while let Ok(mut chunk) = empty_rx.recv() {
                let read = reader.read_chunk(&mut chunk, DEFAULT_CHUNK);
                let last = !matches!(read, Ok(n) if n > 0);
                if matches!(read, Ok(0)) || full_tx.send(read.map(|_| chunk)).is_err() || last {
                    break;
                }
            }
        });
        consume(full_rx, empty_tx, &mut f)
    })
}

/// The consumer's side of [`read_ahead`]. It owns its channel ends, so
/// they hang up (and the reader thread ends) before the scope joins it,
/// whichever way this returns.
fn consume(
    full: Receiver<Result<PointChunk, IoError>>,
    empty: Sender<PointChunk>,
    f: &mut impl FnMut(&PointChunk) -> Result<(), StoreError>,
) -> Result<(), StoreError> {
    for chunk in full.iter() {
        let chunk = chunk?;
        f(&chunk)?;
        let _ = empty.send(chunk);
    }
    Ok(())
}

/// Size and modification time of `path`, to tell whether it changed.
fn stamp(path: &Path) -> Option<(u64, SystemTime)> {
    let meta = std::fs::metadata(path).ok()?;
    Some((meta.len(), meta.modified().ok()?))
}

impl Replay {
    /// Calls `f(first, points)` for consecutive chunks of the `count`
    /// points, in input order.
    pub(super) fn for_each(
        &self,
        reader: &dyn PointReader,
        count: u64,
        f: impl FnMut(u64, &[DVec3]) -> Result<(), StoreError>,
    ) -> Result<(), StoreError> {
        match self {
            Replay::Spill(path) => for_each_spilled(path, count, f),
            Replay::Input(stamp) => for_each_reread(reader, *stamp, count, f),
        }
    }
}

fn for_each_spilled(
    path: &Path,
    count: u64,
    mut f: impl FnMut(u64, &[DVec3]) -> Result<(), StoreError>,
) -> Result<(), StoreError> {
    let file = File::open(path).map_err(|e| StoreError::os(path, e))?;
    let mut input = BufReader::with_capacity(1 << 20, file);
    let mut buf = vec![0u8; DEFAULT_CHUNK * 24];
    let mut pts = Vec::with_capacity(DEFAULT_CHUNK);
    let mut done = 0u64;
    while done < count {
        let n = (count - done).min(DEFAULT_CHUNK as u64) as usize;
        input
            .read_exact(&mut buf[..n * 24])
            .map_err(|e| StoreError::os(path, e))?;
        pts.clear();
        pts.extend(buf[..n * 24].chunks_exact(24).map(|r| {
            let v = |o: usize| f64::from_le_bytes(r[o..o + 8].try_into().unwrap_or([0; 8]));
            DVec3::new(v(0), v(8), v(16))
        }));
        f(done, &pts)?;
        done += n as u64;
    }
    Ok(())
}

fn for_each_reread(
    first: &dyn PointReader,
    stamp: Option<(u64, SystemTime)>,
    count: u64,
    mut f: impl FnMut(u64, &[DVec3]) -> Result<(), StoreError>,
) -> Result<(), StoreError> {
    let path = &first.info().path;
    let changed = || StoreError::Corrupt {
        path: path.clone(),
        reason: "the input changed while it was being read; run again on a file nobody writes"
            .into(),
    };
    if stamp.is_none() || stamp != self::stamp(path) {
        return Err(changed());
    }
    let mut reader = match first.reopen() {
        Some(r) => r?,
        None => return Err(changed()),
    };
    let mut done = 0u64;
    read_ahead(reader.as_mut(), |chunk| {
        if done + chunk.len() as u64 > count {
            return Err(changed());
        }
        f(done, &chunk.xyz)?;
        done += chunk.len() as u64;
        Ok(())
    })?;
    if done != count || stamp != self::stamp(path) {
        return Err(changed());
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::{memory::MemoryReader, open_reader, InvalidPolicy};
    use crate::progress::NoProgress;
    use crate::store::{build_store, BuildOptions, TileTarget, INDEX_FILE, XYZ_FILE};

    /// A binary PLY of `pts` (f32 x y z), every 7th record NaN.
    fn write_ply(path: &Path, pts: &[DVec3]) -> Vec<DVec3> {
        let mut body = format!(
            "ply\nformat binary_little_endian 1.0\nelement vertex {}\n\
             property float x\nproperty float y\nproperty float z\nend_header\n",
            pts.len()
        )
        .into_bytes();
        let mut valid = Vec::new();
        for (i, p) in pts.iter().enumerate() {
            let p = if i % 7 == 3 { DVec3::NAN } else { *p };
            let f = p.as_vec3();
            for v in f.to_array() {
                body.extend_from_slice(&v.to_le_bytes());
            }
            if p.is_finite() {
                valid.push(f.as_dvec3());
            }
        }
        std::fs::write(path, body).unwrap();
        valid
    }

    fn opts() -> BuildOptions {
        BuildOptions {
            tiles: TileTarget::Points(500),
            ..BuildOptions::default()
        }
    }

    #[test]
    fn rereading_the_input_gives_the_store_a_spill_gives() {
        let dir = tempfile::tempdir().unwrap();
        let mut rng = crate::synth::Rng::new(5);
        let pts: Vec<DVec3> = (0..9000)
            .map(|_| DVec3::new(rng.uniform(), rng.uniform(), 0.2 * rng.uniform()))
            .collect();
        let path = dir.path().join("in.ply");
        let valid = write_ply(&path, &pts);
        let mut file = open_reader(&path, InvalidPolicy::Skip).unwrap();
        assert!(matches!(file.reopen(), Some(Ok(_))));
        let reread = build_store(file.as_mut(), &dir.path().join("a"), &opts(), &NoProgress);
        let reread = reread.unwrap();
        let mut copy = MemoryReader::new("in", valid, None);
        assert!(copy.reopen().is_none());
        let spilled = build_store(&mut copy, &dir.path().join("b"), &opts(), &NoProgress).unwrap();
        assert!(reread.tiles().len() > 10);
        assert_eq!(reread.manifest.tiles, spilled.manifest.tiles);
        assert_eq!(reread.manifest.skipped_invalid, 9000 / 7 + 1);
        for file in [XYZ_FILE, INDEX_FILE] {
            let a = std::fs::read(reread.dir.join(file)).unwrap();
            let b = std::fs::read(spilled.dir.join(file)).unwrap();
            assert!(a == b, "{file} differs");
        }
    }

    #[test]
    fn an_input_that_changes_between_passes_is_an_error() {
        let dir = tempfile::tempdir().unwrap();
        let pts: Vec<DVec3> = (0..3000).map(|i| DVec3::new(i as f64, 1.0, 2.0)).collect();
        let path = dir.path().join("in.ply");
        write_ply(&path, &pts);
        let mut file = open_reader(&path, InvalidPolicy::Skip).unwrap();
        let mut sink = AttributeSink::create(dir.path(), Default::default()).unwrap();
        let (count, _, replay) =
            first_pass(file.as_mut(), &dir.path().join("s"), &mut sink, &NoProgress).unwrap();
        assert!(matches!(replay, Replay::Input(Some(_))));
        write_ply(&path, &pts[..2000]);
        let err = replay
            .for_each(file.as_ref(), count, |_, _| Ok(()))
            .unwrap_err();
        assert!(
            err.to_string().contains("changed while it was being read"),
            "{err}"
        );
    }

    #[test]
    fn read_ahead_stops_when_the_consumer_fails() {
        let pts: Vec<DVec3> = (0..5 * DEFAULT_CHUNK)
            .map(|i| DVec3::splat(i as f64))
            .collect();
        let mut reader = MemoryReader::new("cloud", pts, None);
        let mut seen = 0;
        let err = read_ahead(&mut reader, |chunk| {
            seen += chunk.len();
            Err(StoreError::Empty {
                path: "stop".into(),
            })
        });
        assert!(err.is_err());
        assert_eq!(seen, DEFAULT_CHUNK);
    }
}
