//! Fixed-size records sorted out of core: gathered in a buffer of a fixed
//! size, each full buffer sorted and written as a run to a scratch file
//! beside an output, and the runs merged back in order (k-way, through a
//! binary heap; more runs than [`RunSizes::fan_in`] are merged in rounds
//! first). The mesh audit sorts its corner records this way
//! ([`super::audit`]), the projection's seam repair its edge uses
//! (`recon::projection::stitch`). Records are sorted whole, so the merged
//! order does not depend on the buffer size; or, with an [`Order`] that
//! groups, by a key only, and merged a key's block of each run at a time
//! (a heap operation per key and run, not per record): the keys come in
//! order, a key's records in an order the buffer size decides. The audit
//! groups its corners by vertex so (its per-vertex work sorts the few
//! records of a vertex itself): auditing the 1M dragon's open mesh (2.38M
//! triangles, 7.2M corners, 6 runs) took 0.73 s instead of 0.93 sorted
//! whole.
//!
//! RAM: the buffer ([`RunSizes::chunk_bytes`]) while records come, then
//! the merge's read buffers ([`RunSizes::merge_bytes`]); disk: the records
//! (twice while a round of merges runs).

use super::paged::Element;
use super::scratch::scratch_beside;
use rayon::slice::ParallelSliceMut;
use std::cmp::Reverse;
use std::collections::BinaryHeap;
use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::marker::PhantomData;
use std::os::unix::fs::FileExt;
use std::path::{Path, PathBuf};

/// How much memory the sort takes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct RunSizes {
    /// Bytes of records gathered before a sorted run is written.
    pub chunk_bytes: usize,
    /// Most runs merged at once; more are merged in rounds first.
    pub fan_in: usize,
    /// Bytes of read buffers shared by the runs of one merge.
    pub merge_bytes: usize,
}

impl RunSizes {
    /// 16 MiB of records, 256 runs at once through 64 KiB each.
    pub const DEFAULT: RunSizes = RunSizes {
        chunk_bytes: 16 << 20,
        fan_in: 256,
        merge_bytes: 16 << 20,
    };
}

/// How the records of a [`SortedRuns`] are ordered: whole ([`Whole`]), or
/// grouped by a key (a type of the caller's, so the sort's comparisons
/// inline).
pub(crate) trait Order<R> {
    /// Sorted by [`Order::key`] alone, a key's records in no given order.
    const GROUPED: bool;
    /// The key a grouped sort orders by.
    fn key(record: &R) -> u64;
}

/// Records sorted whole.
pub(crate) struct Whole;

impl<R> Order<R> for Whole {
    const GROUPED: bool = false;
    fn key(_: &R) -> u64 {
        0
    }
}

/// A run of sorted records in a scratch file.
#[derive(Clone, Copy, Debug)]
struct Run {
    /// Byte offset of its first record.
    start: u64,
    /// Records it holds.
    len: u64,
}

/// Records waiting to be merged in order.
pub(crate) struct SortedRuns<R, O = Whole> {
    /// The output the scratch files go beside.
    beside: PathBuf,
    sizes: RunSizes,
    buffer: Vec<R>,
    /// The sorted runs written so far, once the buffer first filled.
    runs: Option<(BufWriter<File>, Vec<Run>)>,
    order: PhantomData<O>,
}

impl<R: Element + Ord + Send, O: Order<R>> SortedRuns<R, O> {
    /// A sort whose scratch files go beside `path`.
    pub fn new(path: &Path, sizes: RunSizes) -> Self {
        SortedRuns {
            beside: path.to_path_buf(),
            sizes,
            buffer: Vec::new(),
            runs: None,
            order: PhantomData,
        }
    }

    /// Sorts `records` as `O` says; on every thread of the pool when
    /// `parallel`.
    fn sort(records: &mut [R], parallel: bool) {
        match (O::GROUPED, parallel) {
            (true, false) => records.sort_unstable_by_key(O::key),
            (true, true) => records.par_sort_unstable_by_key(O::key),
            (false, false) => records.sort_unstable(),
            (false, true) => records.par_sort_unstable(),
        }
    }

    /// Records of the buffer before a run is written (at least one).
    fn chunk_records(&self) -> usize {
        (self.sizes.chunk_bytes / R::BYTES).max(1)
    }

    /// Adds a record; writes a run when the buffer is full.
    pub fn push(&mut self, record: R) -> io::Result<()> {
        if self.buffer.capacity() == 0 {
            // Pages never touched cost no RSS: a small sort pays for what
            // it uses.
            self.buffer.reserve_exact(self.chunk_records());
        }
        self.buffer.push(record);
        if self.buffer.len() >= self.chunk_records() {
            self.spill(false)?;
        }
        Ok(())
    }

    /// Sorts the buffer (on every thread when `parallel`) and writes it as
    /// a run.
    fn spill(&mut self, parallel: bool) -> io::Result<()> {
        if self.buffer.is_empty() {
            return Ok(());
        }
        Self::sort(&mut self.buffer, parallel);
        if self.runs.is_none() {
            let file = scratch_beside(&self.beside)?;
            self.runs = Some((BufWriter::with_capacity(1 << 20, file), Vec::new()));
        }
        if let Some((w, runs)) = &mut self.runs {
            let start = runs.last().map_or(0, |r| r.start + r.len * R::BYTES as u64);
            write_records(w, &self.buffer)?;
            runs.push(Run {
                start,
                len: self.buffer.len() as u64,
            });
        }
        self.buffer.clear();
        Ok(())
    }

    /// Calls `each` on every record, in the order `O` says. The last buffer
    /// is sorted on every thread of the pool: the callers merge once the
    /// tiles are done.
    pub fn merge(mut self, mut each: impl FnMut(R) -> io::Result<()>) -> io::Result<()> {
        if self.runs.is_none() {
            // Everything fits one buffer: no run on disk.
            Self::sort(&mut self.buffer, true);
            return self.buffer.iter().try_for_each(|&r| each(r));
        }
        self.spill(true)?;
        self.buffer = Vec::new();
        let Some((w, runs)) = self.runs.take() else {
            return Ok(());
        };
        let file = w.into_inner().map_err(|e| e.into_error())?;
        let (file, runs) = merge_rounds::<R, O>(file, runs, &self.beside, self.sizes)?;
        merge_runs::<R, O>(&file, &runs, self.sizes.merge_bytes, each)
    }
}

/// Appends `records` to `w`, little-endian.
fn write_records<R: Element>(w: &mut impl Write, records: &[R]) -> io::Result<()> {
    let mut bytes = vec![0u8; R::BYTES];
    for r in records {
        r.store(&mut bytes);
        w.write_all(&bytes)?;
    }
    Ok(())
}

/// Merges groups of `sizes.fan_in` runs into longer runs in a new file
/// until at most that many are left.
fn merge_rounds<R: Element + Ord, O: Order<R>>(
    mut file: File,
    mut runs: Vec<Run>,
    beside: &Path,
    sizes: RunSizes,
) -> io::Result<(File, Vec<Run>)> {
    let fan_in = sizes.fan_in.max(2);
    while runs.len() > fan_in {
        let mut w = BufWriter::with_capacity(1 << 20, scratch_beside(beside)?);
        let mut next = Vec::with_capacity(runs.len().div_ceil(fan_in));
        let mut start = 0u64;
        for group in runs.chunks(fan_in) {
            let len: u64 = group.iter().map(|r| r.len).sum();
            merge_runs::<R, O>(&file, group, sizes.merge_bytes, |r| {
                write_records(&mut w, &[r])
            })?;
            next.push(Run { start, len });
            start += len * R::BYTES as u64;
        }
        file = w.into_inner().map_err(|e| e.into_error())?;
        runs = next;
    }
    Ok((file, runs))
}

/// Reads one run's records in order through a buffer of its own.
struct RunReader {
    /// Byte offset of the next record not yet in the buffer.
    at: u64,
    /// Records not yet in the buffer.
    left: u64,
    buf: Vec<u8>,
    /// Bytes of `buf` filled, and the next one to take.
    filled: usize,
    pos: usize,
}

impl RunReader {
    fn new(run: Run, buffer_bytes: usize, record: usize) -> Self {
        let records = (buffer_bytes / record).max(1);
        RunReader {
            at: run.start,
            left: run.len,
            buf: vec![0; records.min(run.len as usize).max(1) * record],
            filled: 0,
            pos: 0,
        }
    }

    fn next<R: Element>(&mut self, file: &File) -> io::Result<Option<R>> {
        if self.pos == self.filled {
            if self.left == 0 {
                return Ok(None);
            }
            let records = (self.buf.len() / R::BYTES).min(self.left as usize);
            let bytes = records * R::BYTES;
            file.read_exact_at(&mut self.buf[..bytes], self.at)?;
            self.at += bytes as u64;
            self.left -= records as u64;
            (self.filled, self.pos) = (bytes, 0);
        }
        let r = R::load(&self.buf[self.pos..self.pos + R::BYTES]);
        self.pos += R::BYTES;
        Ok(Some(r))
    }
}

/// Calls `each` on the records of `runs` (each sorted as `O` says) in
/// that order.
fn merge_runs<R: Element + Ord, O: Order<R>>(
    file: &File,
    runs: &[Run],
    buffer_bytes: usize,
    each: impl FnMut(R) -> io::Result<()>,
) -> io::Result<()> {
    match O::GROUPED {
        true => merge_grouped::<R, O>(file, runs, buffer_bytes, each),
        false => merge(file, runs, buffer_bytes, each),
    }
}

/// The readers of `runs`, sharing `buffer_bytes`.
fn readers<R: Element>(runs: &[Run], buffer_bytes: usize) -> Vec<RunReader> {
    let share = buffer_bytes / runs.len().max(1);
    runs.iter()
        .map(|&r| RunReader::new(r, share, R::BYTES))
        .collect()
}

/// Calls `each` on the records of `runs` (each sorted by `O`'s key) in
/// order of their keys: the heap holds each run's next key, and a run
/// gives all its records of the smallest key at once.
fn merge_grouped<R: Element, O: Order<R>>(
    file: &File,
    runs: &[Run],
    buffer_bytes: usize,
    mut each: impl FnMut(R) -> io::Result<()>,
) -> io::Result<()> {
    let key = O::key;
    let mut readers = readers::<R>(runs, buffer_bytes);
    let mut heads: Vec<Option<R>> = Vec::with_capacity(readers.len());
    let mut heap = BinaryHeap::with_capacity(readers.len());
    for (i, r) in readers.iter_mut().enumerate() {
        let head = r.next::<R>(file)?;
        if let Some(h) = &head {
            heap.push(Reverse((key(h), i)));
        }
        heads.push(head);
    }
    while let Some(Reverse((k, i))) = heap.pop() {
        let mut head = heads[i].take();
        while let Some(r) = head.filter(|r| key(r) == k) {
            each(r)?;
            head = readers[i].next::<R>(file)?;
        }
        if let Some(h) = &head {
            heap.push(Reverse((key(h), i)));
        }
        heads[i] = head;
    }
    Ok(())
}

/// Calls `each` on the records of `runs` (each sorted) in sorted order.
fn merge<R: Element + Ord>(
    file: &File,
    runs: &[Run],
    buffer_bytes: usize,
    mut each: impl FnMut(R) -> io::Result<()>,
) -> io::Result<()> {
    let mut readers = readers::<R>(runs, buffer_bytes);
    let mut heap = BinaryHeap::with_capacity(readers.len());
    for (i, r) in readers.iter_mut().enumerate() {
        if let Some(c) = r.next::<R>(file)? {
            heap.push(Reverse((c, i)));
        }
    }
    while let Some(Reverse((c, i))) = heap.pop() {
        each(c)?;
        if let Some(next) = readers[i].next::<R>(file)? {
            heap.push(Reverse((next, i)));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    /// Random records, and what `O`'s sort gives back of them at a tiny
    /// and at the default size.
    fn sorted_back<O: Order<[u32; 3]>>(seed: u64) -> (Vec<[u32; 3]>, Vec<Vec<[u32; 3]>>) {
        let dir = tempfile::tempdir().unwrap();
        let beside = dir.path().join("out.ply");
        let mut rng = Rng::new(seed);
        let records: Vec<[u32; 3]> = (0..20_000)
            .map(|_| [0; 3].map(|_| rng.below(500) as u32))
            .collect();
        let tiny = RunSizes {
            chunk_bytes: 12 * 37,
            fan_in: 3,
            merge_bytes: 100,
        };
        let back = [tiny, RunSizes::DEFAULT].map(|sizes| {
            let mut runs = SortedRuns::<[u32; 3], O>::new(&beside, sizes);
            for &r in &records {
                runs.push(r).unwrap();
            }
            let mut got = Vec::new();
            runs.merge(|r| {
                got.push(r);
                Ok(())
            })
            .unwrap();
            got
        });
        (records, back.into())
    }

    #[test]
    fn merged_runs_come_back_sorted_whatever_the_sizes() {
        let (mut records, back) = sorted_back::<Whole>(5);
        records.sort_unstable();
        for got in back {
            assert_eq!(got, records);
        }
    }

    /// Grouped by the first element.
    struct First;

    impl Order<[u32; 3]> for First {
        const GROUPED: bool = true;
        fn key(r: &[u32; 3]) -> u64 {
            r[0].into()
        }
    }

    #[test]
    fn grouped_runs_come_back_by_key_whatever_the_sizes() {
        let (mut records, back) = sorted_back::<First>(8);
        records.sort_unstable();
        for mut got in back {
            assert!(got.windows(2).all(|w| w[0][0] <= w[1][0]), "keys in order");
            // The same records, each key's in some order.
            got.sort_unstable();
            assert_eq!(got, records);
        }
    }
}
