//! The store build's one read of its input: every point is validated by
//! its reader, counted, bounded, and written to the input-order columns
//! (the exact coordinates, `super::exact`, and the attributes) as it
//! streams; the later passes (histogram, scatter) read the exact column,
//! never the input again. Reading the input again was cheaper for an
//! uncompressed binary file than spilling a copy, but the exact
//! coordinates must be kept anyway, and they are that copy.

use super::attributes::AttributeSink;
use super::exact::ExactSink;
use super::manifest::Station;
use super::StoreError;
use crate::geom::Aabb;
use crate::io::{IoError, PointChunk, PointReader, ScanStation, DEFAULT_CHUNK};
use crate::progress::Progress;
use crossbeam::channel::{Receiver, Sender};

/// Point ids are u32 in the orientation pass's union-find.
pub const MAX_POINTS: u64 = u32::MAX as u64 - 1;

/// What the first pass learnt besides the columns it wrote.
pub(super) struct Ingested {
    pub count: u64,
    pub bounds: Aabb,
    /// The input's scanner stations by runs of kept points.
    pub stations: Vec<Station>,
}

/// Reads every point of `reader` once into the input-order columns;
/// returns how many there are, their bounds and stations.
pub(super) fn first_pass(
    reader: &mut dyn PointReader,
    exact: &mut ExactSink,
    attributes: &mut AttributeSink,
    progress: &dyn Progress,
) -> Result<Ingested, StoreError> {
    let mut bounds = Aabb::EMPTY;
    let mut count = 0u64;
    progress.begin("read", reader.info().declared_count.unwrap_or(0));
    let path = reader.info().path.clone();
    let mut stations = StationRuns::new(reader.stations());
    read_ahead(reader, |chunk| {
        for p in &chunk.xyz {
            bounds.add(*p);
        }
        stations.add(chunk, count);
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
    Ok(Ingested {
        count,
        bounds,
        stations: stations.runs,
    })
}

/// The stations of a reader's record runs turned into runs of kept
/// points: a skipped record (an E57 invalid state) has no input index, so
/// the kept points' indices are counted here as the chunks pass.
struct StationRuns {
    /// The reader's runs, sorted by first record.
    given: Vec<ScanStation>,
    /// The run the last record fell in (records come in order).
    at: usize,
    runs: Vec<Station>,
    /// Which given run the last of `runs` belongs to.
    last: Option<usize>,
}

impl StationRuns {
    fn new(mut given: Vec<ScanStation>) -> Self {
        given.sort_by_key(|s| s.first_record);
        StationRuns {
            given,
            at: 0,
            runs: Vec::new(),
            last: None,
        }
    }

    /// Files the points of `chunk`, the first of which is kept point
    /// `first` (input index).
    fn add(&mut self, chunk: &PointChunk, first: u64) {
        if self.given.is_empty() {
            return;
        }
        for k in 0..chunk.len() {
            let record = match &chunk.indices {
                Some(ix) => ix.get(k).copied().unwrap_or(u64::MAX),
                None => chunk.first_index + k as u64,
            };
            let ends = |s: &ScanStation| s.first_record.saturating_add(s.records);
            if self
                .given
                .get(self.at)
                .is_none_or(|s| record < s.first_record)
            {
                // Out of order (no reader does this): search from the start.
                self.at = 0;
            }
            while self.given.get(self.at).is_some_and(|s| record >= ends(s)) {
                self.at += 1;
            }
            let Some(s) = self.given.get(self.at).filter(|s| record >= s.first_record) else {
                continue;
            };
            let index = first + k as u64;
            match self.runs.last_mut() {
                Some(r) if self.last == Some(self.at) && r.end == index => r.end += 1,
                _ => {
                    self.runs.push(Station {
                        first: index,
                        end: index + 1,
                        position: s.position.to_array(),
                    });
                    self.last = Some(self.at);
                }
            }
        }
    }
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
    fn station_runs_follow_the_kept_points() {
        let st = |first_record, records, x| ScanStation {
            first_record,
            records,
            position: DVec3::new(x, 0.0, 0.0),
        };
        let mut runs = StationRuns::new(vec![st(5, 5, 2.0), st(0, 5, 1.0)]);
        // Records 0..10, record 3 and 6 skipped: kept points 0..8.
        let chunk = PointChunk {
            first_index: 0,
            xyz: vec![DVec3::ZERO; 8],
            indices: Some(vec![0, 1, 2, 4, 5, 7, 8, 9]),
            ..PointChunk::default()
        };
        runs.add(&chunk, 0);
        let got: Vec<(u64, u64, f64)> = runs
            .runs
            .iter()
            .map(|r| (r.first, r.end, r.position[0]))
            .collect();
        assert_eq!(got, vec![(0, 4, 1.0), (4, 8, 2.0)]);
        // Nothing given: nothing kept.
        let mut none = StationRuns::new(Vec::new());
        none.add(&chunk, 0);
        assert!(none.runs.is_empty());
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
