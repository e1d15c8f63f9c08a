//! Tile forests on disk: each tile's sorted forest edges are appended as one
//! run to a scratch file, and a k-way merge streams all runs back in global
//! edge order, so the union of forests (about one edge per point) never has
//! to fit in memory.

use super::forest::Edge;
use super::unionfind::ParityUnionFind;
use crate::io::{cleanup, IoError};
use crate::pipeline::Progress;
use crossbeam::channel;
use std::cmp::Reverse;
use std::collections::BinaryHeap;
use std::fs::File;
use std::io::{BufWriter, Read, Write};
use std::ops::Range;
use std::os::unix::fs::FileExt;
use std::path::{Path, PathBuf};

/// Edges handed to the union-find at a time (see
/// [`ParityUnionFind::union_batch`]).
const UNION_BATCH: usize = 512;
/// Edges per batch passed from the merging thread to the union-find.
const HANDOFF: usize = 8 * UNION_BATCH;
/// Read buffers of the k-way merge, shared among the runs.
const MERGE_BUFFER: usize = 16 << 20;

/// An edge's slots and flip parity, as the union-find takes them.
type Pair = (u32, u32, bool);

/// Sorted runs of edges in one scratch file, removed on drop. Runs pushed
/// with [`EdgeRuns::push_tile_run`] also log the slots their edges reach
/// outside their tile's core (a second scratch file): the boundary the
/// external orientation needs, gathered while the forests are at hand.
pub struct EdgeRuns {
    path: PathBuf,
    out: BufWriter<File>,
    runs: Vec<(u64, u64)>,
    written: u64,
    outside: Option<(PathBuf, BufWriter<File>)>,
    /// Both scratch files, for an interrupt handler.
    _cleanup: [cleanup::Registered; 2],
}

impl EdgeRuns {
    pub fn create(path: &Path) -> Result<Self, IoError> {
        let file = File::options()
            .read(true)
            .write(true)
            .create(true)
            .truncate(true)
            .open(path)
            .map_err(|e| IoError::os(path, e))?;
        Ok(EdgeRuns {
            path: path.to_path_buf(),
            out: BufWriter::with_capacity(1 << 20, file),
            runs: Vec::new(),
            written: 0,
            outside: None,
            _cleanup: [
                cleanup::register(path),
                cleanup::register(&path.with_extension("outside")),
            ],
        })
    }

    /// Appends one tile's run (as [`Self::push_run`]) and logs every slot
    /// of it outside `core`, the tile's store range.
    pub fn push_tile_run(&mut self, edges: &[Edge], core: Range<u64>) -> Result<(), IoError> {
        self.push_run(edges)?;
        if self.outside.is_none() {
            let path = self.path.with_extension("outside");
            let file = File::create(&path).map_err(|e| IoError::os(&path, e))?;
            self.outside = Some((path, BufWriter::with_capacity(1 << 20, file)));
        }
        if let Some((path, log)) = &mut self.outside {
            for s in edges.iter().flat_map(|e| e.slots) {
                if !core.contains(&u64::from(s)) {
                    log.write_all(&s.to_le_bytes())
                        .map_err(|e| IoError::os(&*path, e))?;
                }
            }
        }
        Ok(())
    }

    /// The slots logged by [`Self::push_tile_run`] (and `extra`), sorted,
    /// each once. The log is read in chunks and compacted as it goes, so
    /// memory stays near the result's size.
    pub fn outside_slots(&mut self, extra: &[u32]) -> Result<Vec<u32>, IoError> {
        let mut all = extra.to_vec();
        let Some((path, log)) = self.outside.take() else {
            all.sort_unstable();
            all.dedup();
            return Ok(all);
        };
        let file = log
            .into_inner()
            .map_err(|e| IoError::os(&path, e.into_error()))?;
        drop(file);
        let mut input = std::io::BufReader::with_capacity(
            1 << 20,
            File::open(&path).map_err(|e| IoError::os(&path, e))?,
        );
        let mut chunk = vec![0u8; 1 << 22];
        loop {
            let n = read_full(&mut input, &mut chunk).map_err(|e| IoError::os(&path, e))?;
            all.extend(
                chunk[..n - n % 4]
                    .chunks_exact(4)
                    .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]])),
            );
            // A vertex is met once per tile it borders: compacting keeps
            // the list near its final size.
            if n < chunk.len() || all.len() > all.capacity() / 2 {
                all.sort_unstable();
                all.dedup();
            }
            if n < chunk.len() {
                break;
            }
        }
        let _ = std::fs::remove_file(&path);
        all.shrink_to_fit();
        Ok(all)
    }

    /// Appends one run; `edges` must be sorted by [`Edge::key`].
    pub fn push_run(&mut self, edges: &[Edge]) -> Result<(), IoError> {
        for e in edges {
            self.out
                .write_all(&e.to_bytes())
                .map_err(|err| IoError::os(&self.path, err))?;
        }
        self.runs.push((self.written, edges.len() as u64));
        self.written += edges.len() as u64;
        Ok(())
    }

    pub fn edges(&self) -> u64 {
        self.written
    }

    /// Position in the file (in edges) of run `r`'s first edge: runs lie
    /// one after another, so `run_start(r) + i` numbers every edge.
    pub fn run_start(&self, r: usize) -> u64 {
        self.runs[r].0
    }

    /// Makes every pushed run readable by [`Self::read_run`].
    pub fn flush(&mut self) -> Result<(), IoError> {
        self.out.flush().map_err(|e| IoError::os(&self.path, e))
    }

    /// The edges of run `r` (after [`Self::flush`]).
    pub fn read_run(&self, r: usize) -> Result<Vec<Edge>, IoError> {
        let (start, len) = self.runs[r];
        read_edges(self.out.get_ref(), start, len as usize, &self.path)
    }

    /// Kruskal over all runs: joins every edge's slots in `uf` with its flip
    /// parity, in global key order, reporting progress as stage `stage`.
    /// With two or more threads the merge (reading, decoding, the heap) runs
    /// on a second thread, handing over batches in order, while this one
    /// does the unions; the unions and their order are the same.
    pub fn union_all(
        self,
        uf: &mut ParityUnionFind,
        stage: &str,
        progress: &dyn Progress,
    ) -> Result<(), IoError> {
        progress.begin(stage, self.edges());
        let result = if rayon::current_num_threads() > 1 {
            self.union_pipelined(uf, progress)
        } else {
            let mut batch = Vec::with_capacity(UNION_BATCH);
            let merged = self.merge(MERGE_BUFFER, |e| {
                batch.push((e.slots[0], e.slots[1], e.flips()));
                if batch.len() == UNION_BATCH {
                    uf.union_batch(&batch);
                    batch.clear();
                    progress.advance(UNION_BATCH as u64);
                }
            });
            uf.union_batch(&batch);
            merged
        };
        progress.end();
        result
    }

    fn union_pipelined(
        self,
        uf: &mut ParityUnionFind,
        progress: &dyn Progress,
    ) -> Result<(), IoError> {
        let (full_tx, full_rx) = channel::bounded::<Vec<Pair>>(4);
        let (empty_tx, empty_rx) = channel::unbounded::<Vec<Pair>>();
        std::thread::scope(|s| {
            let merger = s.spawn(move || {
                let mut batch = Vec::with_capacity(HANDOFF);
                let merged = self.merge(MERGE_BUFFER, |e| {
                    batch.push((e.slots[0], e.slots[1], e.flips()));
                    if batch.len() == HANDOFF {
                        let next = empty_rx.try_recv().unwrap_or_default();
                        // The receiver lives until this thread is joined.
                        let _ = full_tx.send(std::mem::replace(&mut batch, next));
                    }
                });
                let _ = full_tx.send(batch);
                merged
            });
            for mut batch in full_rx {
                batch.chunks(UNION_BATCH).for_each(|b| uf.union_batch(b));
                progress.advance(batch.len() as u64);
                batch.clear();
                let _ = empty_tx.send(batch);
            }
            merger
                .join()
                .unwrap_or_else(|p| std::panic::resume_unwind(p))
        })
    }
    /// Calls `f` on every edge of every run in global [`Edge::key`] order.
    /// `buffer_bytes` is shared among the runs' read buffers.
    pub fn merge(mut self, buffer_bytes: usize, mut f: impl FnMut(Edge)) -> Result<(), IoError> {
        self.merge_numbered(buffer_bytes, |_, e| f(e))
    }

    /// As [`Self::merge`], each edge with its position in the file (see
    /// [`Self::run_start`]).
    pub fn merge_numbered(
        &mut self,
        buffer_bytes: usize,
        mut f: impl FnMut(u64, Edge),
    ) -> Result<(), IoError> {
        self.out.flush().map_err(|e| IoError::os(&self.path, e))?;
        let file = self.out.get_ref();
        let per_run = (buffer_bytes / Edge::BYTES / self.runs.len().max(1)).max(64);
        let mut cursors: Vec<RunCursor> = self
            .runs
            .iter()
            .map(|&(start, len)| RunCursor {
                next: start,
                end: start + len,
                buf: Vec::new(),
                pos: 0,
            })
            .collect();
        let mut heap = BinaryHeap::new();
        for (r, c) in cursors.iter_mut().enumerate() {
            if let Some(e) = c.peek(file, per_run, &self.path)? {
                heap.push(Reverse((e.key(), r)));
            }
        }
        while let Some(Reverse((_, r))) = heap.pop() {
            let c = &mut cursors[r];
            let e = c.buf[c.pos];
            let at = c.next - (c.buf.len() - c.pos) as u64;
            c.pos += 1;
            f(at, e);
            if let Some(e) = c.peek(file, per_run, &self.path)? {
                heap.push(Reverse((e.key(), r)));
            }
        }
        Ok(())
    }
}

impl Drop for EdgeRuns {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.path);
        if let Some((path, _)) = &self.outside {
            let _ = std::fs::remove_file(path);
        }
    }
}

/// Reads until `buf` is full or the input ends; returns the bytes read.
fn read_full(r: &mut impl Read, buf: &mut [u8]) -> std::io::Result<usize> {
    let mut n = 0;
    while n < buf.len() {
        match r.read(&mut buf[n..]) {
            Ok(0) => break,
            Ok(k) => n += k,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(n)
}

struct RunCursor {
    next: u64,
    end: u64,
    buf: Vec<Edge>,
    pos: usize,
}

impl RunCursor {
    /// The run's next edge, refilling the buffer from disk when it is empty.
    fn peek(&mut self, file: &File, per_run: usize, path: &Path) -> Result<Option<Edge>, IoError> {
        if self.pos == self.buf.len() {
            let n = (self.end - self.next).min(per_run as u64) as usize;
            if n == 0 {
                return Ok(None);
            }
            self.buf = read_edges(file, self.next, n, path)?;
            self.pos = 0;
            self.next += n as u64;
        }
        Ok(Some(self.buf[self.pos]))
    }
}

/// `n` edges from position `start` (in edges) of `file`.
fn read_edges(file: &File, start: u64, n: usize, path: &Path) -> Result<Vec<Edge>, IoError> {
    let mut bytes = vec![0u8; n * Edge::BYTES];
    file.read_exact_at(&mut bytes, start * Edge::BYTES as u64)
        .map_err(|e| IoError::os(path, e))?;
    Ok(bytes
        .chunks_exact(Edge::BYTES)
        .map(|c| {
            let mut a = [0u8; Edge::BYTES];
            a.copy_from_slice(c);
            Edge::from_bytes(&a)
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn merge_yields_global_order() {
        let dir = tempfile::tempdir().unwrap();
        let mut runs = EdgeRuns::create(&dir.path().join("e")).unwrap();
        let mut all = Vec::new();
        for r in 0..5u32 {
            let mut edges: Vec<Edge> = (0..100u32)
                .map(|i| {
                    Edge::new(
                        r * 1000 + i,
                        r * 1000 + i + 1,
                        ((i * 7919 + r * 31) % 97) as f64 / 97.0,
                    )
                })
                .collect();
            edges.sort_unstable_by_key(Edge::key);
            runs.push_run(&edges).unwrap();
            all.extend(edges);
        }
        all.sort_unstable_by_key(Edge::key);
        let mut merged = Vec::new();
        runs.merge(1024, |e| merged.push(e)).unwrap();
        assert_eq!(merged, all);
    }
}
