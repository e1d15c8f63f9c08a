//! Per-vertex state of unbounded size kept in a scratch file: an array of
//! plain values (`u32` parents and counts, f64 sums, f64 positions) read
//! and written through a cache of a fixed number of pages of 1024 elements
//! (clock eviction, dirty pages written back), and the disjoint sets of
//! [`super::pieces`] and [`super::audit`] on top of it.
//!
//! Why not a memory map: `--mem` is a promise about peak RSS, and mapped
//! pages count in it once touched; with memory to spare the kernel never
//! evicts them, so a map of the whole array grows with the mesh. Positioned
//! reads and writes go through the OS page cache, which is not the
//! process's RSS. The stitcher numbers vertices tile by tile and a tile's
//! triangles reach back only to the seam vertices of its neighbours, so the
//! pages in use are the current tile's, the roots' and a few per seam: a
//! cache of a few MiB misses rarely (measured in the module's tests and on
//! the 10M dragon, see ARCHITECTURE.md).
//!
//! Per element held in RAM: the page table's 4 bytes per 1024 elements.

use std::fs::File;
use std::io;
use std::os::unix::fs::FileExt;

/// Elements per page (4 KiB of `u32`, 24 KiB of positions).
const PAGE: usize = 1024;

/// RAM held per element: the page table's entry per page.
pub const TABLE_BYTES_PER_ELEMENT: f64 = 4.0 / PAGE as f64;

/// A value a [`Paged`] array holds: a fixed number of little-endian bytes,
/// all zero for `Default`.
pub(crate) trait Element: Copy + Default {
    /// Bytes of one element in the file.
    const BYTES: usize;
    /// The element stored in `bytes` (`BYTES` long).
    fn load(bytes: &[u8]) -> Self;
    /// Writes the element into `bytes` (`BYTES` long).
    fn store(&self, bytes: &mut [u8]);
}

/// The `N` bytes at the start of `bytes` (zeros past its end; callers
/// always pass at least `N`).
fn array<const N: usize>(bytes: &[u8]) -> [u8; N] {
    let mut a = [0u8; N];
    let n = N.min(bytes.len());
    a[..n].copy_from_slice(&bytes[..n]);
    a
}

impl Element for u32 {
    const BYTES: usize = 4;
    fn load(bytes: &[u8]) -> Self {
        u32::from_le_bytes(array(bytes))
    }
    fn store(&self, bytes: &mut [u8]) {
        bytes[..4].copy_from_slice(&self.to_le_bytes());
    }
}

impl Element for f64 {
    const BYTES: usize = 8;
    fn load(bytes: &[u8]) -> Self {
        f64::from_le_bytes(array(bytes))
    }
    fn store(&self, bytes: &mut [u8]) {
        bytes[..8].copy_from_slice(&self.to_le_bytes());
    }
}

/// A triangle's corners, or a corner with its neighbours.
impl Element for [u32; 3] {
    const BYTES: usize = 12;
    fn load(bytes: &[u8]) -> Self {
        [0, 4, 8].map(|at| u32::load(&bytes[at..]))
    }
    fn store(&self, bytes: &mut [u8]) {
        for (c, at) in self.iter().zip([0, 4, 8]) {
            c.store(&mut bytes[at..]);
        }
    }
}

impl Element for u64 {
    const BYTES: usize = 8;
    fn load(bytes: &[u8]) -> Self {
        u64::from_le_bytes(array(bytes))
    }
    fn store(&self, bytes: &mut [u8]) {
        bytes[..8].copy_from_slice(&self.to_le_bytes());
    }
}

/// A position, `x, y, z`.
impl Element for [f64; 3] {
    const BYTES: usize = 24;
    fn load(bytes: &[u8]) -> Self {
        [0, 8, 16].map(|at| f64::load(&bytes[at..]))
    }
    fn store(&self, bytes: &mut [u8]) {
        for (c, at) in self.iter().zip([0, 8, 16]) {
            c.store(&mut bytes[at..]);
        }
    }
}

/// A growable array of `T` in a file, `T::default()` (all zero bytes)
/// where never written.
pub(crate) struct Paged<T: Element> {
    file: File,
    /// Pages the file holds, the last maybe in part (later pages read as
    /// zeros).
    file_pages: u64,
    /// Page number -> slot + 1 (0: not cached).
    table: Vec<u32>,
    slots: Vec<Slot<T>>,
    capacity: usize,
    hand: usize,
    /// The last page looked up and its slot: most accesses repeat it.
    last: Option<(u64, usize)>,
    bytes: Vec<u8>,
}

/// The `u32` array of the small-piece filter and the disjoint sets.
pub(crate) type PagedU32 = Paged<u32>;

struct Slot<T> {
    page: u64,
    dirty: bool,
    referenced: bool,
    data: Box<[T]>,
}

impl<T: Element> Paged<T> {
    /// An array over the scratch file `file` (empty), caching at most
    /// `cache_bytes` of pages (at least one).
    pub fn new(file: File, cache_bytes: usize) -> Self {
        Self::over(file, 0, cache_bytes)
    }

    /// An array over `file`, which already holds `len` elements written
    /// in this layout (a spool of values, read back by index).
    pub fn over(file: File, len: u64, cache_bytes: usize) -> Self {
        let page_bytes = PAGE * T::BYTES;
        Paged {
            file,
            file_pages: len.div_ceil(PAGE as u64),
            table: Vec::new(),
            slots: Vec::new(),
            capacity: (cache_bytes / page_bytes).max(1),
            hand: 0,
            last: None,
            bytes: vec![0; page_bytes],
        }
    }

    fn page_bytes() -> u64 {
        (PAGE * T::BYTES) as u64
    }

    pub fn get(&mut self, i: u64) -> io::Result<T> {
        let slot = self.slot_of(i / PAGE as u64)?;
        Ok(self.slots[slot].data[i as usize % PAGE])
    }

    pub fn set(&mut self, i: u64, value: T) -> io::Result<()> {
        let slot = self.slot_of(i / PAGE as u64)?;
        let s = &mut self.slots[slot];
        s.data[i as usize % PAGE] = value;
        s.dirty = true;
        Ok(())
    }

    /// The slot holding `page`, loading it (and evicting another) if needed.
    fn slot_of(&mut self, page: u64) -> io::Result<usize> {
        if let Some((p, slot)) = self.last {
            if p == page {
                return Ok(slot);
            }
        }
        let entry = self.table.get(page as usize).copied().unwrap_or(0);
        let slot = if entry > 0 {
            entry as usize - 1
        } else {
            self.load(page)?
        };
        self.slots[slot].referenced = true;
        self.last = Some((page, slot));
        Ok(slot)
    }

    fn load(&mut self, page: u64) -> io::Result<usize> {
        let slot = if self.slots.len() < self.capacity {
            self.slots.push(Slot {
                page,
                dirty: false,
                referenced: false,
                data: vec![T::default(); PAGE].into_boxed_slice(),
            });
            self.slots.len() - 1
        } else {
            let victim = self.victim();
            self.write_back(victim)?;
            self.table[self.slots[victim].page as usize] = 0;
            victim
        };
        self.read_page(page, slot)?;
        if self.table.len() <= page as usize {
            self.table.resize(page as usize + 1, 0);
        }
        self.table[page as usize] = slot as u32 + 1;
        Ok(slot)
    }

    /// Clock: the first slot not referenced since the hand last passed.
    fn victim(&mut self) -> usize {
        loop {
            let i = self.hand;
            self.hand = (self.hand + 1) % self.slots.len();
            let s = &mut self.slots[i];
            if !s.referenced {
                return i;
            }
            s.referenced = false;
        }
    }

    fn write_back(&mut self, slot: usize) -> io::Result<()> {
        let s = &mut self.slots[slot];
        if !s.dirty {
            return Ok(());
        }
        for (b, v) in self.bytes.chunks_exact_mut(T::BYTES).zip(s.data.iter()) {
            v.store(b);
        }
        self.file
            .write_all_at(&self.bytes, s.page * Self::page_bytes())?;
        self.file_pages = self.file_pages.max(s.page + 1);
        s.dirty = false;
        Ok(())
    }

    fn read_page(&mut self, page: u64, slot: usize) -> io::Result<()> {
        if self.last.is_some_and(|(_, s)| s == slot) {
            self.last = None;
        }
        let s = &mut self.slots[slot];
        s.page = page;
        s.dirty = false;
        if page >= self.file_pages {
            s.data.fill(T::default());
            return Ok(());
        }
        // The last page of a spool may be short: the rest reads as zeros.
        let mut filled = 0;
        let at = page * Self::page_bytes();
        while filled < self.bytes.len() {
            match self
                .file
                .read_at(&mut self.bytes[filled..], at + filled as u64)
            {
                Ok(0) => break,
                Ok(n) => filled += n,
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(e) => return Err(e),
            }
        }
        self.bytes[filled..].fill(0);
        for (v, b) in s.data.iter_mut().zip(self.bytes.chunks_exact(T::BYTES)) {
            *v = T::load(b);
        }
        Ok(())
    }
}

/// Disjoint sets over `0..len` in a [`PagedU32`], with the semantics of
/// [`super::union_find::DisjointSets`]: union links the larger root under
/// the smaller, so a set's root is its smallest member whatever the order
/// of unions (the filter's output does not depend on the cache). An element
/// stores its parent + 1, 0 for a root, so unwritten pages are singletons.
pub(crate) struct ExternalSets {
    parent: PagedU32,
    len: u64,
}

impl ExternalSets {
    pub fn new(file: File, cache_bytes: usize) -> Self {
        ExternalSets {
            parent: PagedU32::new(file, cache_bytes),
            len: 0,
        }
    }

    pub fn len(&self) -> u64 {
        self.len
    }

    /// Adds singleton sets up to `n` members in all.
    pub fn grow(&mut self, n: u64) {
        self.len = self.len.max(n);
    }

    fn parent(&mut self, x: u64) -> io::Result<u64> {
        Ok(match self.parent.get(x)? {
            0 => x,
            p => p as u64 - 1,
        })
    }

    /// The root of `x`'s set, halving the path on the way.
    pub fn find(&mut self, mut x: u64) -> io::Result<u64> {
        loop {
            let p = self.parent(x)?;
            if p == x {
                return Ok(x);
            }
            let gp = self.parent(p)?;
            if gp != p {
                self.parent.set(x, gp as u32 + 1)?;
            }
            x = gp;
        }
    }

    /// Joins the sets of `a` and `b`; whether they were apart (so the
    /// sets number one fewer).
    pub fn union(&mut self, a: u64, b: u64) -> io::Result<bool> {
        let (ra, rb) = (self.find(a)?, self.find(b)?);
        if ra == rb {
            return Ok(false);
        }
        let (lo, hi) = if ra < rb { (ra, rb) } else { (rb, ra) };
        self.parent.set(hi, lo as u32 + 1)?;
        Ok(true)
    }
}

/// What joining two members with a parity found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Joined {
    /// They were apart: their sets are one now.
    Merged,
    /// They were together with that parity already.
    Agreed,
    /// They were together with the other parity: nothing changed.
    Conflict,
}

/// Disjoint sets over dense `u64` members in a `Paged<u64>`, each member
/// with a parity bit to its parent (joining `a` and `b` with parity `p`
/// says "a and b differ by p"), so a find gives a member's parity to its
/// root: a winding by union-find, out of core. As [`ExternalSets`], union
/// links the larger root under the smaller, so a set's root is its
/// smallest member whatever the order of joins. An element stores
/// `(parent + 1) << 1 | parity`, 0 for a root.
pub(crate) struct ExternalParitySets {
    link: Paged<u64>,
}

impl ExternalParitySets {
    pub fn new(file: File, cache_bytes: usize) -> Self {
        ExternalParitySets {
            link: Paged::new(file, cache_bytes),
        }
    }

    /// `x`'s parent and its parity to it (a root is its own, parity 0).
    fn parent(&mut self, x: u64) -> io::Result<(u64, bool)> {
        Ok(match self.link.get(x)? {
            0 => (x, false),
            v => ((v >> 1) - 1, v & 1 == 1),
        })
    }

    fn set_parent(&mut self, x: u64, parent: u64, parity: bool) -> io::Result<()> {
        self.link.set(x, (parent + 1) << 1 | u64::from(parity))
    }

    /// The root of `x`'s set and `x`'s parity to it, halving the path on
    /// the way (a member skipping its parent takes the sum of both bits).
    pub fn find(&mut self, mut x: u64) -> io::Result<(u64, bool)> {
        let mut acc = false;
        loop {
            let (p, px) = self.parent(x)?;
            if p == x {
                return Ok((x, acc));
            }
            let (g, pp) = self.parent(p)?;
            if g == p {
                return Ok((p, acc ^ px));
            }
            self.set_parent(x, g, px ^ pp)?;
            acc ^= px ^ pp;
            x = g;
        }
    }

    /// Joins `a` and `b` as differing by `parity`.
    pub fn join(&mut self, a: u64, b: u64, parity: bool) -> io::Result<Joined> {
        let ((ra, pa), (rb, pb)) = (self.find(a)?, self.find(b)?);
        if ra == rb {
            return Ok(if pa ^ pb == parity {
                Joined::Agreed
            } else {
                Joined::Conflict
            });
        }
        let (lo, hi) = if ra < rb { (ra, rb) } else { (rb, ra) };
        self.set_parent(hi, lo, pa ^ pb ^ parity)?;
        Ok(Joined::Merged)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::union_find::DisjointSets;

    /// A tiny cache (2 pages) over 20 pages of values, against a `Vec`.
    #[test]
    fn paged_array_equals_a_vec_through_evictions() {
        let mut paged = PagedU32::new(tempfile::tempfile().unwrap(), 2 * 4 * PAGE);
        let n = 20 * PAGE as u64;
        let mut plain = vec![0u32; n as usize];
        let mut state = 12345u64;
        for step in 0..200_000u64 {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let i = (state >> 33) % n;
            if step % 3 == 0 {
                plain[i as usize] = step as u32;
                paged.set(i, step as u32).unwrap();
            } else {
                assert_eq!(paged.get(i).unwrap(), plain[i as usize], "index {i}");
            }
        }
        for i in 0..n {
            assert_eq!(paged.get(i).unwrap(), plain[i as usize], "index {i}");
        }
    }

    /// Random joins with parities, seeded, through a cache of 4 pages,
    /// against a brute-force labelling: the same sets, the same relative
    /// parities, and a conflict exactly where the labels disagree.
    #[test]
    fn external_parity_sets_equal_brute_force_labels() {
        for seed in [3u64, 11, 2024] {
            let n = 4000usize;
            let mut ext = ExternalParitySets::new(tempfile::tempfile().unwrap(), 4 * 8 * PAGE);
            // Brute force: a set label and a parity per member, relabelled
            // whole on every merge.
            let mut label: Vec<usize> = (0..n).collect();
            let mut bit = vec![false; n];
            let mut state = seed;
            let mut next = || {
                state = state
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                state >> 33
            };
            let (mut conflicts, mut merged) = (0, 0);
            for _ in 0..6000 {
                let (a, b) = (next() as usize % n, next() as usize % n);
                let parity = next() % 2 == 1;
                let want = if label[a] != label[b] {
                    let (from, to, flip) = (label[b], label[a], bit[a] ^ bit[b] ^ parity);
                    for m in 0..n {
                        if label[m] == from {
                            label[m] = to;
                            bit[m] ^= flip;
                        }
                    }
                    merged += 1;
                    Joined::Merged
                } else if bit[a] ^ bit[b] == parity {
                    Joined::Agreed
                } else {
                    conflicts += 1;
                    Joined::Conflict
                };
                assert_eq!(ext.join(a as u64, b as u64, parity).unwrap(), want);
            }
            assert!(conflicts > 0 && merged > 0, "{conflicts} {merged}");
            for x in 0..n {
                let (rx, px) = ext.find(x as u64).unwrap();
                let (r0, p0) = ext.find(label[x] as u64).unwrap();
                assert_eq!(rx, r0, "seed {seed}: {x}");
                assert_eq!(px ^ p0, bit[x] ^ bit[label[x]], "seed {seed}: {x}");
                // The root is the set's smallest member.
                assert!(rx <= x as u64);
            }
        }
    }

    /// Random unions, seeded: the same roots as the in-memory sets.
    #[test]
    fn external_sets_equal_the_in_memory_ones() {
        for seed in [1u64, 7, 99] {
            let n = 5000usize;
            let mut ext = ExternalSets::new(tempfile::tempfile().unwrap(), 4 * PAGE);
            let mut mem = DisjointSets::<u32>::new(n);
            ext.grow(n as u64);
            let mut state = seed;
            let mut next = || {
                state = state
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                (state >> 33) as usize % n
            };
            for _ in 0..3000 {
                let (a, b) = (next(), next());
                mem.union(a, b);
                ext.union(a as u64, b as u64).unwrap();
            }
            for x in 0..n {
                assert_eq!(
                    ext.find(x as u64).unwrap(),
                    mem.find(x) as u64,
                    "seed {seed}"
                );
            }
        }
    }
}
