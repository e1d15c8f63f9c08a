//! The store build's one read of its input: every point is validated by
//! its reader, counted, bounded, and written to the input-order columns
//! (the exact coordinates, `super::exact`, and the attributes) as it
//! streams; the later passes (histogram, scatter) read the exact column,
//! never the input again. Reading the input again was cheaper for an
//! uncompressed binary file than spilling a copy, but the exact
//! coordinates must be kept anyway, and they are that copy.

use super::attributes::AttributeSink;
use super::exact::ExactSink;
use super::StoreError;
use crate::geom::Aabb;
use crate::io::{IoError, PointChunk, PointReader, DEFAULT_CHUNK};
use crate::progress::Progress;
use crossbeam::channel::{Receiver, Sender};

/// Point ids are u32 in the orientation pass's union-find.
pub const MAX_POINTS: u64 = u32::MAX as u64 - 1;

/// Reads every point of `reader` once into the input-order columns;
/// returns how many there are and their bounds.
pub(super) fn first_pass(
    reader: &mut dyn PointReader,
    exact: &mut ExactSink,
    attributes: &mut AttributeSink,
    progress: &dyn Progress,
) -> Result<(u64, Aabb), StoreError> {
    let mut bounds = Aabb::EMPTY;
    let mut count = 0u64;
    progress.begin("read", reader.info().declared_count.unwrap_or(0));
    let path = reader.info().path.clone();
    read_ahead(reader, |chunk| {
        for p in &chunk.xyz {
            bounds.add(*p);
        }
        exact.write(&chunk.xyz)?;
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
    progress.end();
    Ok((count, bounds))
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::memory::MemoryReader;
    use glam::DVec3;

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
