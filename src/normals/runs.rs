//! Tile forests on disk: each tile's sorted forest edges are appended as one
//! run to a scratch file, and a k-way merge streams all runs back in global
//! edge order, so the union of forests (about one edge per point) never has
//! to fit in memory. Runs only ever read back whole, one tile at a time (the
//! external orientation's), are packed to about half the bytes
//! ([`Layout::Packed`]).

use super::forest::Edge;
use super::packed::{pack, unpack, CoreIds};
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

/// How a scratch file lays out its runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Layout {
    /// Fixed records of [`Edge::BYTES`]: the runs merge in global key order.
    Records,
    /// Packed ([`super::packed`], about 11 bytes an edge where a record
    /// takes 24): each run is read back whole, with its tile's core ids
    /// ([`EdgeRuns::read_run`]); never merged.
    Packed,
}

impl Layout {
    /// The layout of tile forests for an orientation that goes external
    /// (read per tile: packed) or not (merged: records).
    pub fn for_orientation(external: bool) -> Self {
        if external {
            Layout::Packed
        } else {
            Layout::Records
        }
    }
}

/// Where one run lies: its edges' numbers and its bytes in the file, and
/// the tile core its ids are packed against (empty for a plain run).
#[derive(Clone, Debug)]
struct Run {
    first: u64,
    len: u64,
    offset: u64,
    bytes: u64,
    core: Range<u32>,
}

/// Sorted runs of edges in one scratch file, removed on drop. Runs pushed
/// with [`EdgeRuns::push_tile_run`] also log the slots their edges reach
/// outside their tile's core (a second scratch file): the boundary the
/// external orientation needs, gathered while the forests are at hand.
pub struct EdgeRuns {
    path: PathBuf,
    out: BufWriter<File>,
    layout: Layout,
    runs: Vec<Run>,
    /// Edges written.
    written: u64,
    /// Bytes written.
    offset: u64,
    packing: Vec<u8>,
    outside: Option<(PathBuf, BufWriter<File>)>,
    /// Both scratch files, for an interrupt handler.
    _cleanup: [cleanup::Registered; 2],
}

impl EdgeRuns {
    pub fn create(path: &Path, layout: Layout) -> Result<Self, IoError> {
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
            layout,
            runs: Vec::new(),
            written: 0,
            offset: 0,
            packing: Vec::new(),
            outside: None,
            _cleanup: [
                cleanup::register(path),
                cleanup::register(&path.with_extension("outside")),
            ],
        })
    }

    /// Appends one tile's run (as [`Self::push_run`]) and logs every slot
    /// of it outside `core`, the tile's store range. `core_ids` are the
    /// core's input ids (`PointStore::read_indices`), which a packed run
    /// leaves out where they are the store's (a packed run given none
    /// keeps every id).
    pub fn push_tile_run(
        &mut self,
        edges: &[Edge],
        core: Range<u64>,
        core_ids: &[u64],
    ) -> Result<(), IoError> {
        let range = match (u32::try_from(core.start), u32::try_from(core.end)) {
            (Ok(a), Ok(b)) => a..b,
            _ => 0..0,
        };
        self.push(edges, range, core_ids)?;
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
        self.push(edges, 0..0, &[])
    }

    fn push(&mut self, edges: &[Edge], core: Range<u32>, core_ids: &[u64]) -> Result<(), IoError> {
        let bytes = match self.layout {
            Layout::Records => {
                for e in edges {
                    self.out
                        .write_all(&e.to_bytes())
                        .map_err(|err| IoError::os(&self.path, err))?;
                }
                (edges.len() * Edge::BYTES) as u64
            }
            Layout::Packed => {
                self.packing.clear();
                let ids = CoreIds {
                    range: &core,
                    ids: core_ids,
                };
                pack(edges, ids, &mut self.packing);
                self.out
                    .write_all(&self.packing)
                    .map_err(|err| IoError::os(&self.path, err))?;
                self.packing.len() as u64
            }
        };
        self.runs.push(Run {
            first: self.written,
            len: edges.len() as u64,
            offset: self.offset,
            bytes,
            core,
        });
        self.written += edges.len() as u64;
        self.offset += bytes;
        Ok(())
    }

    pub fn edges(&self) -> u64 {
        self.written
    }

    /// Position in the file (in edges) of run `r`'s first edge: runs lie
    /// one after another, so `run_start(r) + i` numbers every edge.
    pub fn run_start(&self, r: usize) -> u64 {
        self.runs[r].first
    }

    /// Makes every pushed run readable by [`Self::read_run`].
    pub fn flush(&mut self) -> Result<(), IoError> {
        self.out.flush().map_err(|e| IoError::os(&self.path, e))
    }

    /// The edges of run `r` (after [`Self::flush`]); `core_ids` as given
    /// to [`Self::push_tile_run`] (a run of records needs none).
    pub fn read_run(&self, r: usize, core_ids: &[u64]) -> Result<Vec<Edge>, IoError> {
        let run = &self.runs[r];
        let file = self.out.get_ref();
        if self.layout == Layout::Records {
            return read_edges(file, run.first, run.len as usize, &self.path);
        }
        let mut bytes = vec![0u8; run.bytes as usize];
        file.read_exact_at(&mut bytes, run.offset)
            .map_err(|e| IoError::os(&self.path, e))?;
        let ids = CoreIds {
            range: &run.core,
            ids: core_ids,
        };
        unpack(&bytes, run.len as usize, ids).map_err(|i| IoError::BadRecord {
            path: self.path.clone(),
            record: run.first + i as u64,
            reason: "a packed forest edge does not read back (scratch file changed?)".into(),
        })
    }

    /// Gives run `r`'s disk blocks back to the file system: the caller has
    /// read it for the last time, and must not read it again (the file
    /// keeps its size and reads zeros there, which need not fail to
    /// decode). Where the file system cannot punch holes the blocks stay
    /// until the file is removed, as before; only the scratch peak is
    /// higher.
    #[cfg(target_os = "linux")]
    pub fn release_run(&self, r: usize) -> Result<(), IoError> {
        use rustix::fs::{fallocate, FallocateFlags};
        let run = &self.runs[r];
        let flags = FallocateFlags::PUNCH_HOLE | FallocateFlags::KEEP_SIZE;
        match fallocate(self.out.get_ref(), flags, run.offset, run.bytes) {
            Ok(()) | Err(rustix::io::Errno::OPNOTSUPP) => Ok(()),
            Err(e) => Err(IoError::os(&self.path, e.into())),
        }
    }

    /// As on Linux, without the holes: the blocks stay until the file goes.
    #[cfg(not(target_os = "linux"))]
    pub fn release_run(&self, _: usize) -> Result<(), IoError> {
        Ok(())
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
        if self.layout == Layout::Packed {
            let why = "packed runs are read one tile at a time, never merged";
            return Err(IoError::os(&self.path, std::io::Error::other(why)));
        }
        let file = self.out.get_ref();
        let per_run = (buffer_bytes / Edge::BYTES / self.runs.len().max(1)).max(64);
        let mut cursors: Vec<RunCursor> = self
            .runs
            .iter()
            .map(|run| RunCursor {
                next: run.first,
                end: run.first + run.len,
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
        let mut runs = EdgeRuns::create(&dir.path().join("e"), Layout::Records).unwrap();
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

    /// Three tiles of 100 points whose ids are a permutation; each edge
    /// from a core point, a tenth of them to the next tile's points.
    fn tile_forests() -> (Vec<u64>, Vec<Vec<Edge>>) {
        let ids: Vec<u64> = (0..300u64).map(|s| (s * 181 + 7) % 300).collect();
        let forests = (0..3u32)
            .map(|t| {
                let mut edges: Vec<Edge> = (0..100u32)
                    .map(|i| {
                        let x = t * 100 + i;
                        let y = if i % 10 == 0 {
                            (x + 100) % 300
                        } else {
                            t * 100 + (i * 37) % 100
                        };
                        let end = |s: u32| [ids[s as usize] as u32, s];
                        let cost = f64::from((i * 7919) % 97) / 97.0;
                        Edge::between(end(x), end(y), cost, if i % 3 == 0 { -1.0 } else { 1.0 })
                    })
                    .collect();
                edges.sort_unstable_by_key(Edge::key);
                edges
            })
            .collect();
        (ids, forests)
    }

    #[test]
    fn packed_tile_runs_read_back_whole_and_refuse_a_merge() {
        let (ids, forests) = tile_forests();
        let dir = tempfile::tempdir().unwrap();
        let mut packed = EdgeRuns::create(&dir.path().join("p"), Layout::Packed).unwrap();
        let mut records = EdgeRuns::create(&dir.path().join("r"), Layout::Records).unwrap();
        for (t, f) in forests.iter().enumerate() {
            let core = t as u64 * 100..(t as u64 + 1) * 100;
            let core_ids = &ids[core.start as usize..core.end as usize];
            packed.push_tile_run(f, core.clone(), core_ids).unwrap();
            records.push_tile_run(f, core, &[]).unwrap();
        }
        packed.flush().unwrap();
        records.flush().unwrap();
        let size = |p: &str| std::fs::metadata(dir.path().join(p)).unwrap().len();
        assert!(size("p") * 2 < size("r"), "{} vs {}", size("p"), size("r"));
        for (t, f) in forests.iter().enumerate() {
            let core_ids = &ids[t * 100..(t + 1) * 100];
            assert_eq!(&packed.read_run(t, core_ids).unwrap(), f);
            assert_eq!(&records.read_run(t, &[]).unwrap(), f);
            assert_eq!(packed.run_start(t), records.run_start(t));
        }
        // Read with the wrong core ids, a run does not come back as it was.
        let wrong: Vec<u64> = ids[..100].iter().map(|i| i + 1).collect();
        assert_ne!(packed.read_run(0, &wrong).ok().as_ref(), Some(&forests[0]));
        assert_eq!(packed.outside_slots(&[]).unwrap().len(), 30);
        assert!(packed.merge(1024, |_| {}).is_err());
    }

    #[test]
    fn a_released_run_gives_its_blocks_back_and_spares_the_others() {
        use std::os::unix::fs::MetadataExt;
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("e");
        let mut runs = EdgeRuns::create(&path, Layout::Records).unwrap();
        let run = |r: u32| -> Vec<Edge> {
            (0..20_000u32)
                .map(|i| Edge::new(r * 100_000 + i, r * 100_000 + i + 1, f64::from(i) / 2e4))
                .collect()
        };
        for r in 0..3 {
            runs.push_run(&run(r)).unwrap();
        }
        runs.flush().unwrap();
        let blocks = || std::fs::metadata(&path).unwrap().blocks();
        let before = blocks();
        runs.release_run(1).unwrap();
        // 480 kB given back, in 512-byte blocks (less the partial ones at
        // the run's two ends).
        assert!(before - blocks() > 900, "{before} -> {}", blocks());
        assert_eq!(runs.read_run(0, &[]).unwrap(), run(0));
        assert_eq!(runs.read_run(2, &[]).unwrap(), run(2));
    }
}
