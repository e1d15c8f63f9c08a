//! Winding a stream of triangles out of core, flattest crossing first, and
//! cutting the short twists that keep an orientable surface from being
//! wound.
//!
//! Paper 4 outputs a 2-manifold triangle set and leaves its winding open
//! (it handles non-orientable surfaces, a Moebius strip); a mesh needs one
//! winding. Walking the triangles breadth first winds a surface as its
//! walk meets it, so where a small ring of triangles has turned over round
//! a hole (the 1M noisy dragon: every odd cycle of triangles 14-31 steps
//! long, ringing a boundary loop of 6-329 edges) the edge the walk meets
//! last is left unwound, wherever that is. Here the dual edges (every edge
//! two triangles share, `super::fans::Twin`) are taken **flattest first**
//! (the angle between the two triangles' normals once wound alike) into a
//! union-find with parities: an edge that joins two triangles already
//! wound apart closes an odd cycle whose every other crossing is flatter,
//! so it lies on the cycle's sharpest crease. Such an edge is cut (its
//! worse triangle left out: the one whose sharpest other crossing is
//! sharper) when some odd closed walk through it is short beside its
//! surface ([`twist_steps`]: a quarter of the square root of its set's
//! triangles, at least [`TWIST_STEPS`]): a twist round a hole. A longer
//! odd walk is the surface's own (a Moebius band's runs round the whole
//! band: 205 steps at 2k points, 3.3 times the root of its 3,832
//! triangles; 696 at 20k, 3.5 times), and its edge stays unwound and
//! counted. The triangles left are wound again by the same order, and
//! each set of the union-find is turned to a positive signed volume.
//!
//! Cutting is a deviation from paper 4, which keeps every triangle it
//! selects: where its selection turns a ring over round a hole (its
//! delta-dense condition, delta < r_max / 2, fails in sparse or thin
//! places), an orientable surface would come out non-orientable, which
//! most tools downstream refuse; the cut costs about 0.007 % of the
//! triangles on the noisy dragon.
//!
//! Tiling: the order is the edges' angle (quantized to [`BINS_PER_RADIAN`])
//! then their vertices' input-order ids, the normals are computed by the
//! caller from the corners in input order, and ties between triangles go
//! to their corners' input ids, so the result depends on the triangles
//! alone, not on the store order or the order they arrive in (tiled ==
//! untiled).
//!
//! Bounded memory: the dual edges are sorted on disk (`super::runs`), the
//! union-find, each triangle's three neighbours and each vertex's input id
//! are paged arrays (`super::paged`); RAM holds their caches and the edges
//! found unwound. The flattest-first order reaches the union-find at
//! random, so its cache takes the whole of it when the caller's room
//! allows (the tiles' memory, free by then), and pays page reads beyond.

use super::fans::Twin;
use super::paged::{Element, ExternalParitySets, Joined, Paged};
use super::runs::{RunSizes, SortedRuns};
use super::scratch::scratch_beside;
use glam::DVec3;
use std::collections::HashSet;
use std::io::{self, BufReader, BufWriter, Read, Seek, Write};
use std::path::Path;

/// Longest odd closed walk of triangles always cut as a twist (see the
/// module doc): twice the longest on the 1M dragon (31), a third of the
/// smallest Moebius band's (205).
pub(crate) const TWIST_STEPS: usize = 64;

/// Longest odd walk searched for, whatever the set's size.
const MOST_TWIST_STEPS: usize = 1024;

/// Most triangle-and-parity states a search holds (about 8 MiB): a search
/// whose walks of one length reach past it stops there, the walk found
/// long (on a surface, walks of `k` steps reach about `k^2` triangles, so
/// this is met near 300 steps). Checked between lengths, so it does not
/// depend on the order neighbours are listed in.
const MOST_WALK_STATES: usize = 1 << 18;

/// Longest odd closed walk cut as a twist in a set of `triangles`: a
/// quarter of their square root, at least [`TWIST_STEPS`], at most
/// [`MOST_TWIST_STEPS`]. Scale-free: a twist's walk rings a hole, and its
/// length in triangles grows with the sampling density as the root of the
/// surface's triangles does (the 10M dragon's twists are three times the
/// 1M's); a band's walk runs its whole length, which is the root of its
/// triangles times the root of its length over its width, above one for
/// any band longer than wide.
fn twist_steps(triangles: u32) -> usize {
    ((f64::from(triangles).sqrt() / 4.0) as usize).clamp(TWIST_STEPS, MOST_TWIST_STEPS)
}

/// Angle bins per radian of the dual edges' order (0.05 degrees each):
/// fine enough that two crossings of one short cycle rarely share a bin,
/// coarse enough that a bin's edges sweep the union-find in order.
pub(crate) const BINS_PER_RADIAN: f64 = 3600.0 / std::f64::consts::PI;

/// RAM of the union-find's page cache at the least (the whole of it up to
/// 1M triangles); more when the caller's room allows.
const SETS_CACHE: usize = 8 << 20;
/// RAM of the neighbours', the sets' sizes', the sums' and a caller's
/// spool's page caches.
pub(crate) const SMALL_CACHE: usize = 1 << 20;
/// The dual edges' sort: a smaller buffer than the fans' (it fills while
/// their merge reads).
const DUAL_SIZES: RunSizes = RunSizes {
    chunk_bytes: 8 << 20,
    fan_in: 256,
    merge_bytes: 8 << 20,
};

/// RAM the seam side holds after the tiles, at its peak: during the fans'
/// merge its read buffers, the dual edges' sort buffer and the caches of
/// the neighbours and the spool; during the dual edges' merge their read
/// buffers, the union-find's cache and the small ones; then the searches
/// for odd walks (their states, 32 B each with the set's overhead).
pub(crate) const RESIDENT_BYTES: u64 = max(
    RunSizes::DEFAULT.merge_bytes + DUAL_SIZES.chunk_bytes + 2 * SMALL_CACHE,
    SETS_CACHE + 4 * SMALL_CACHE + max(DUAL_SIZES.merge_bytes, 32 * MOST_WALK_STATES),
) as u64;

const fn max(a: usize, b: usize) -> usize {
    if a > b {
        a
    } else {
        b
    }
}

/// Scratch disk per triangle at the seam side's peak, during the fans'
/// merge (`super::fans`): the caller's spool, the three edge uses, the
/// sorted dual edges (1.5 per triangle), the neighbours and the vertices'
/// input ids (8 B a vertex, half a vertex a triangle). After it the uses
/// are gone and the dual edges' copy (17 B each), the union-find (8 B,
/// twice) and the sums (9 B) take less than they did.
pub(crate) const SCRATCH_PER_TRIANGLE: u64 =
    Spooled::BYTES as u64 + 3 * 24 + 3 * Dual::BYTES as u64 / 2 + Across::BYTES as u64 + 4;

/// A triangle as the caller spools it: its corners as it wound them and
/// six times its signed volume about the origin, so wound.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Spooled {
    pub corners: [u32; 3],
    pub volume6: f64,
}

impl Element for Spooled {
    const BYTES: usize = 20;
    fn load(bytes: &[u8]) -> Self {
        Spooled {
            corners: <[u32; 3]>::load(bytes),
            volume6: f64::load(&bytes[12..]),
        }
    }
    fn store(&self, bytes: &mut [u8]) {
        self.corners.store(bytes);
        self.volume6.store(&mut bytes[12..]);
    }
}

/// A unit normal packed in 32 bits (octahedral, 16 bits a coordinate:
/// within 0.01 degrees), for [`super::fans::Fans::add`]'s tag; a zero or
/// non-finite normal (a degenerate triangle) packs to a mark that unpacks
/// to zero.
pub(crate) fn pack_normal(n: DVec3) -> u32 {
    let l1 = n.x.abs() + n.y.abs() + n.z.abs();
    if !(l1 > 0.0 && l1.is_finite()) {
        return NO_NORMAL;
    }
    let (mut u, mut v) = (n.x / l1, n.y / l1);
    if n.z < 0.0 {
        (u, v) = ((1.0 - v.abs()) * sign(u), (1.0 - u.abs()) * sign(v));
    }
    let q = |x: f64| (x.clamp(-1.0, 1.0) * 32767.0).round() as i16 as u16 as u32;
    q(u) << 16 | q(v)
}

const NO_NORMAL: u32 = 0x8000_8000;

fn sign(x: f64) -> f64 {
    if x >= 0.0 {
        1.0
    } else {
        -1.0
    }
}

fn unpack_normal(packed: u32) -> DVec3 {
    let (pu, pv) = ((packed >> 16) as u16 as i16, packed as u16 as i16);
    if pu == i16::MIN || pv == i16::MIN {
        return DVec3::ZERO;
    }
    let (mut u, mut v) = (pu as f64 / 32767.0, pv as f64 / 32767.0);
    let z = 1.0 - u.abs() - v.abs();
    if z < 0.0 {
        (u, v) = ((1.0 - v.abs()) * sign(u), (1.0 - u.abs()) * sign(v));
    }
    DVec3::new(u, v, z).normalize_or_zero()
}

/// A dual edge in the winding's order: angle bin, then the edge.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord)]
struct Dual {
    bin: u16,
    /// The edge's vertices as input ids, lower first.
    low: u64,
    high: u64,
    a: u64,
    b: u64,
    same_way: bool,
}

impl Element for Dual {
    const BYTES: usize = 35;
    fn load(bytes: &[u8]) -> Self {
        Dual {
            bin: u16::from_le_bytes([bytes[0], bytes[1]]),
            low: u64::load(&bytes[2..]),
            high: u64::load(&bytes[10..]),
            a: u64::load(&bytes[18..]),
            b: u64::load(&bytes[26..]),
            same_way: bytes[34] != 0,
        }
    }
    fn store(&self, bytes: &mut [u8]) {
        bytes[..2].copy_from_slice(&self.bin.to_le_bytes());
        self.low.store(&mut bytes[2..]);
        self.high.store(&mut bytes[10..]);
        self.a.store(&mut bytes[18..]);
        self.b.store(&mut bytes[26..]);
        bytes[34] = u8::from(self.same_way);
    }
}

/// A triangle's neighbours across its edges (`t + 1`, 0: none), each
/// crossing's angle bin, and whether each runs their edge the same way.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Across {
    next: [u64; 3],
    bin: [u16; 3],
    same_way: u8,
}

impl Across {
    /// The neighbours, with the crossing's bin and same-way bit.
    fn crossings(&self) -> impl Iterator<Item = (u64, u16, bool)> + '_ {
        (0..3)
            .filter(|&k| self.next[k] != 0)
            .map(|k| (self.next[k] - 1, self.bin[k], self.same_way >> k & 1 == 1))
    }
}

impl Element for Across {
    const BYTES: usize = 31;
    fn load(bytes: &[u8]) -> Self {
        Across {
            next: [0, 8, 16].map(|at| u64::load(&bytes[at..])),
            bin: [24, 26, 28].map(|at| u16::from_le_bytes([bytes[at], bytes[at + 1]])),
            same_way: bytes[30],
        }
    }
    fn store(&self, bytes: &mut [u8]) {
        for (n, at) in self.next.iter().zip([0, 8, 16]) {
            n.store(&mut bytes[at..]);
        }
        for (b, at) in self.bin.iter().zip([24, 26, 28]) {
            bytes[at..at + 2].copy_from_slice(&b.to_le_bytes());
        }
        bytes[30] = self.same_way;
    }
}

/// A winding set's signed volume so far and whether a triangle of it was
/// met.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Sum {
    volume6: f64,
    seen: bool,
}

impl Element for Sum {
    const BYTES: usize = 9;
    fn load(bytes: &[u8]) -> Self {
        Sum {
            volume6: f64::load(bytes),
            seen: bytes[8] != 0,
        }
    }
    fn store(&self, bytes: &mut [u8]) {
        self.volume6.store(bytes);
        bytes[8] = u8::from(self.seen);
    }
}

/// Gathers the dual edges of a triangle stream (see the module doc).
pub(crate) struct Untwist {
    duals: SortedRuns<Dual>,
    surface: Surface,
    beside: std::path::PathBuf,
}

/// What the winding reads round a triangle: its neighbours, and every
/// vertex's input-order id (the tie-break that does not depend on the
/// tiling, as store indices do).
struct Surface {
    across: Paged<Across>,
    ids: Paged<u64>,
}

impl Surface {
    /// Input-order id of vertex `v` (a store index).
    fn id(&mut self, v: u32) -> io::Result<u64> {
        // Stored + 1 so that a vertex never given reads as an error, not
        // as the first point.
        match self.ids.get(u64::from(v))? {
            0 => Err(io::Error::other(format!(
                "vertex {v} of a triangle was never given its input id"
            ))),
            id => Ok(id - 1),
        }
    }

    /// Triangle `t`'s corners as input ids, sorted.
    fn key(&mut self, spool: &mut Paged<Spooled>, t: u64) -> io::Result<[u64; 3]> {
        let corners = spool.get(t)?.corners;
        let mut ids = [
            self.id(corners[0])?,
            self.id(corners[1])?,
            self.id(corners[2])?,
        ];
        ids.sort_unstable();
        Ok(ids)
    }
}

/// The winding found: per triangle, whether to turn it over.
pub(crate) struct Winding {
    sets: ExternalParitySets,
    sums: Paged<Sum>,
    /// Triangles left out (the fans' and the twists' cuts), increasing.
    pub removed: Vec<u64>,
    /// Triangles cut at short twists (with the fans they took along).
    pub cut: u64,
    /// Winding sets (connected by shared edges) of the triangles kept.
    pub components: u64,
    /// Sets holding an edge that could not be wound.
    pub non_orientable: u64,
    /// Edges left unwound (each on an odd walk longer than a twist's,
    /// [`twist_steps`]).
    pub unwound: u64,
}

impl Winding {
    /// Whether triangle `t` (kept) is turned over: its parity to its set's
    /// root, and the whole set once more when its volume is negative (a
    /// closed surface faces outward; an open one away from the origin).
    pub fn flip(&mut self, t: u64) -> io::Result<bool> {
        let (root, parity) = self.sets.find(t)?;
        Ok(parity ^ (self.sums.get(root)?.volume6 < 0.0))
    }
}

/// Whether `t` is in the increasing list `list`.
fn listed(list: &[u64], t: u64) -> bool {
    list.binary_search(&t).is_ok()
}

impl Untwist {
    /// Scratch files go beside `path`.
    pub fn new(path: &Path) -> io::Result<Self> {
        Ok(Untwist {
            duals: SortedRuns::new(path, DUAL_SIZES),
            surface: Surface {
                across: Paged::new(scratch_beside(path)?, SMALL_CACHE),
                ids: Paged::new(scratch_beside(path)?, SMALL_CACHE),
            },
            beside: path.to_path_buf(),
        })
    }

    /// The input-order ids of the vertices from store index `first` on.
    pub fn add_ids(&mut self, first: u64, ids: &[u64]) -> io::Result<()> {
        for (v, &id) in (first..).zip(ids) {
            self.surface.ids.set(v, id + 1)?;
        }
        Ok(())
    }

    /// An edge two triangles share, its uses tagged with their normals
    /// ([`pack_normal`]) with the corners in input order.
    pub fn add(&mut self, twin: &Twin) -> io::Result<()> {
        let same_way = twin.same_way();
        let (low, high) = (self.surface.id(twin.low)?, self.surface.id(twin.high)?);
        let mut normals = [DVec3::ZERO; 2];
        for (n, e) in normals.iter_mut().zip(&twin.uses) {
            // As its triangle is wound: the input order's normal, turned
            // when the winding (from low to high when forward, in store
            // order) is not a rotation of the input order. Exact, so the
            // angle's bits do not depend on the tiling.
            let apex = self.surface.id(e.apex)?;
            let rotation = (apex < low.min(high) || apex > low.max(high)) == (low < high);
            *n = unpack_normal(e.tag);
            if e.forward != rotation {
                *n = -*n;
            }
        }
        // Wound alike, flat triangles' normals agree.
        let cos = normals[0].dot(normals[1]) * if same_way { -1.0 } else { 1.0 };
        let bin = (cos.clamp(-1.0, 1.0).acos() * BINS_PER_RADIAN).round() as u16;
        let [a, b] = twin.uses.map(|u| u.triangle);
        self.duals.push(Dual {
            bin,
            low: low.min(high),
            high: low.max(high),
            a,
            b,
            same_way,
        })?;
        for (t, other) in [(a, b), (b, a)] {
            let mut x = self.surface.across.get(t)?;
            if let Some(k) = (0..3).find(|&k| x.next[k] == 0) {
                x.next[k] = other + 1;
                x.bin[k] = bin;
                x.same_way |= u8::from(same_way) << k;
                self.surface.across.set(t, x)?;
            }
        }
        Ok(())
    }

    /// Winds the `triangles` of the stream but those `left_out`
    /// (increasing); `spool` holds each as the caller wound it; the
    /// union-find may cache up to `room` bytes (`None`: all of it).
    pub fn wind(
        self,
        triangles: u64,
        left_out: &[u64],
        spool: &mut Paged<Spooled>,
        room: Option<u64>,
    ) -> io::Result<Winding> {
        let Untwist {
            duals,
            mut surface,
            beside,
        } = self;
        let whole = (triangles as usize)
            .saturating_mul(8)
            .saturating_add(1 << 16);
        let cache = room.map_or(whole, |r| whole.min(SETS_CACHE.max(r as usize / 2)));
        let mut copy = BufWriter::with_capacity(1 << 20, scratch_beside(&beside)?);
        let mut sets = ExternalParitySets::new(scratch_beside(&beside)?, cache);
        let mut conflicts = Vec::new();
        duals.merge(|d| {
            if listed(left_out, d.a) || listed(left_out, d.b) {
                return Ok(());
            }
            copy.write_all(&d.a.to_le_bytes())?;
            copy.write_all(&d.b.to_le_bytes())?;
            copy.write_all(&[u8::from(d.same_way)])?;
            if sets.join(d.a, d.b, d.same_way)? == Joined::Conflict {
                conflicts.push(d);
            }
            Ok(())
        })?;
        let cut = if conflicts.is_empty() {
            Vec::new()
        } else {
            let sizes = set_sizes(&mut sets, triangles, left_out, &beside)?;
            cut_twists(&mut surface, spool, &conflicts, left_out, &mut sets, sizes)?
        };
        let mut unwound: Vec<u64> = conflicts.iter().map(|d| d.a).collect();
        if !cut.is_empty() {
            drop(sets);
            sets = ExternalParitySets::new(scratch_beside(&beside)?, cache);
            unwound = rewind(copy, &cut, &mut sets)?;
        }
        let mut removed: Vec<u64> = left_out.iter().chain(&cut).copied().collect();
        removed.sort_unstable();
        removed.dedup();
        let mut winding = Winding {
            sets,
            sums: Paged::new(scratch_beside(&beside)?, SMALL_CACHE),
            removed,
            cut: cut.len() as u64,
            components: 0,
            non_orientable: 0,
            unwound: unwound.len() as u64,
        };
        winding.sum(triangles, spool)?;
        let mut roots = Vec::with_capacity(unwound.len());
        for t in unwound {
            roots.push(winding.sets.find(t)?.0);
        }
        roots.sort_unstable();
        roots.dedup();
        winding.non_orientable = roots.len() as u64;
        Ok(winding)
    }
}

/// The triangles to cut for the `conflicts` (in the winding's order) that
/// lie on short odd walks: of each such edge's two triangles, the one
/// that takes fewer with it ([`with_fans`]), a tie to the worse
/// ([`worse`]). Increasing.
fn cut_twists(
    surface: &mut Surface,
    spool: &mut Paged<Spooled>,
    conflicts: &[Dual],
    left_out: &[u64],
    sets: &mut ExternalParitySets,
    mut sizes: Paged<u32>,
) -> io::Result<Vec<u64>> {
    let mut cut: Vec<u64> = Vec::new();
    for d in conflicts {
        let gone = |t: u64| listed(left_out, t) || listed(&cut, t);
        if gone(d.a) || gone(d.b) {
            continue;
        }
        let steps = twist_steps(sizes.get(sets.find(d.a)?.0)?);
        if !odd_walk(&mut surface.across, d, steps, gone)? {
            continue;
        }
        let mut a = with_fans(surface, spool, d.a, gone)?;
        let mut b = with_fans(surface, spool, d.b, gone)?;
        let worse = worse(surface, d, spool, left_out)?;
        if b.len() < a.len() || (b.len() == a.len() && worse == d.b) {
            std::mem::swap(&mut a, &mut b);
        }
        cut.extend(a.iter().copied());
        cut.sort_unstable();
        cut.dedup();
        let gone = |t: u64| listed(left_out, t) || listed(&cut, t);
        let islands = islands(&mut surface.across, &a, gone)?;
        cut.extend(islands);
        cut.sort_unstable();
        cut.dedup();
    }
    Ok(cut)
}

/// The pieces of at most [`FAN_STEPS`] triangles that `taken` (just cut)
/// leaves joined to the rest by no edge: a piece held by a cut triangle
/// alone would hang on by a vertex (a non-manifold vertex; on a noisy
/// torus, 2 triangles so).
fn islands(
    across: &mut Paged<Across>,
    taken: &[u64],
    gone: impl Fn(u64) -> bool,
) -> io::Result<Vec<u64>> {
    let mut out: Vec<u64> = Vec::new();
    for &x in taken {
        for (start, _, _) in across.get(x)?.crossings() {
            if gone(start) || out.contains(&start) {
                continue;
            }
            let mut piece = vec![start];
            let mut at = 0;
            while at < piece.len() && piece.len() <= FAN_STEPS {
                for (n, _, _) in across.get(piece[at])?.crossings() {
                    if !gone(n) && !piece.contains(&n) {
                        piece.push(n);
                    }
                }
                at += 1;
            }
            if piece.len() <= FAN_STEPS {
                out.extend(piece);
            }
        }
    }
    Ok(out)
}

/// Of a conflict's two triangles, the one to cut: the one whose sharpest
/// other crossings (sharpest first) are sharper; a tie to the larger
/// corners in input order.
fn worse(
    surface: &mut Surface,
    d: &Dual,
    spool: &mut Paged<Spooled>,
    left_out: &[u64],
) -> io::Result<u64> {
    let mut key = |t: u64, partner: u64| -> io::Result<([u16; 2], [u64; 3])> {
        let mut bins = [0u16; 2];
        let mut others: Vec<u16> = surface
            .across
            .get(t)?
            .crossings()
            .filter(|&(n, _, _)| n != partner && !listed(left_out, n))
            .map(|(_, bin, _)| bin)
            .collect();
        others.sort_unstable_by(|x, y| y.cmp(x));
        for (slot, bin) in bins.iter_mut().zip(others) {
            *slot = bin;
        }
        Ok((bins, surface.key(spool, t)?))
    };
    let (ka, kb) = (key(d.a, d.b)?, key(d.b, d.a)?);
    Ok(if ka >= kb { d.a } else { d.b })
}

/// Longest fan walked round a corner of a triangle cut (a vertex of the
/// noisy dragon has about 6 triangles; a walk this long is not a twist's).
const FAN_STEPS: usize = 64;

/// Triangle `t` and what must go with it so that no corner of `t` is left
/// with two fans (a non-manifold vertex): at a corner on a boundary whose
/// fan `t` splits, the smaller side (a tie: the side of the larger
/// corners in input order). At the dragon's twists the triangle cut has a
/// corner on the hole it rings 98 % of the time: 50 cuts alone made 76
/// non-manifold vertices.
fn with_fans(
    surface: &mut Surface,
    spool: &mut Paged<Spooled>,
    t: u64,
    gone: impl Fn(u64) -> bool,
) -> io::Result<Vec<u64>> {
    let mut out = vec![t];
    let corners = spool.get(t)?.corners;
    for k in 0..3 {
        let c = corners[k];
        let mut sides = Vec::with_capacity(2);
        for toward in [corners[(k + 1) % 3], corners[(k + 2) % 3]] {
            match fan_side(&mut surface.across, spool, t, c, toward, &gone)? {
                Some(side) => sides.push(side),
                // A closed fan round `c`: taking `t` opens it, no split.
                None => break,
            }
        }
        if let [x, y] = &mut sides[..] {
            if !x.is_empty() && !y.is_empty() {
                let kx = (x.len(), surface.key(spool, x[0])?);
                let ky = (y.len(), surface.key(spool, y[0])?);
                out.append(if kx <= ky { x } else { y });
            }
        }
    }
    out.sort_unstable();
    out.dedup();
    Ok(out)
}

/// The triangles round corner `c` from `t` across its edge to `toward`,
/// in order, up to a boundary (`Some`); `None` when the walk comes back to
/// `t` (a closed fan) or runs past [`FAN_STEPS`].
fn fan_side(
    across: &mut Paged<Across>,
    spool: &mut Paged<Spooled>,
    t: u64,
    c: u32,
    mut toward: u32,
    gone: &impl Fn(u64) -> bool,
) -> io::Result<Option<Vec<u64>>> {
    let mut side = Vec::new();
    let mut at = t;
    for _ in 0..FAN_STEPS {
        let mut next = None;
        for (n, _, _) in across.get(at)?.crossings() {
            let corners = spool.get(n)?.corners;
            if !gone(n) && corners.contains(&c) && corners.contains(&toward) {
                next = Some((n, corners));
                break;
            }
        }
        let Some((n, corners)) = next else {
            return Ok(Some(side));
        };
        if n == t {
            return Ok(None);
        }
        side.push(n);
        at = n;
        toward = corners
            .into_iter()
            .find(|&v| v != c && v != toward)
            .unwrap_or(toward);
    }
    Ok(None)
}

/// Triangles per set of the first pass (by root), those `left_out` not
/// counted.
fn set_sizes(
    sets: &mut ExternalParitySets,
    triangles: u64,
    left_out: &[u64],
    beside: &Path,
) -> io::Result<Paged<u32>> {
    let mut sizes = Paged::new(scratch_beside(beside)?, SMALL_CACHE);
    let mut out = left_out.iter().peekable();
    for t in 0..triangles {
        if out.next_if_eq(&&t).is_some() {
            continue;
        }
        let root = sets.find(t)?.0;
        let n: u32 = sizes.get(root)?;
        sizes.set(root, n.saturating_add(1))?;
    }
    Ok(sizes)
}

/// Whether some odd closed walk of at most `steps` triangles runs through
/// `d`: a walk from `d.b` back to `d.a` whose crossings, with `d`, cannot
/// all be wound (breadth first over triangle and parity, never through a
/// triangle `gone`).
fn odd_walk(
    across: &mut Paged<Across>,
    d: &Dual,
    steps: usize,
    gone: impl Fn(u64) -> bool,
) -> io::Result<bool> {
    let target = (d.a, !d.same_way);
    let mut seen = HashSet::from([(d.b, false)]);
    let mut frontier = vec![(d.b, false)];
    for _ in 1..steps {
        let mut next = Vec::new();
        for (t, parity) in frontier {
            for (w, _, same_way) in across.get(t)?.crossings() {
                let state = (w, parity ^ same_way);
                if state == target {
                    return Ok(true);
                }
                if !gone(w) && seen.insert(state) {
                    next.push(state);
                }
            }
        }
        if next.is_empty() || seen.len() > MOST_WALK_STATES {
            break;
        }
        frontier = next;
    }
    Ok(false)
}

/// The second pass: the dual edges again in the same order (from the
/// first pass's copy), those of `cut` triangles left out; the triangles
/// of each edge still unwound.
fn rewind(
    copy: BufWriter<std::fs::File>,
    cut: &[u64],
    sets: &mut ExternalParitySets,
) -> io::Result<Vec<u64>> {
    let mut file = copy.into_inner().map_err(|e| e.into_error())?;
    file.rewind()?;
    let mut reader = BufReader::with_capacity(1 << 20, file);
    let mut record = [0u8; 17];
    let mut unwound = Vec::new();
    loop {
        match reader.read_exact(&mut record) {
            Ok(()) => {}
            Err(e) if e.kind() == io::ErrorKind::UnexpectedEof => break,
            Err(e) => return Err(e),
        }
        let (a, b) = (u64::load(&record), u64::load(&record[8..]));
        if listed(cut, a) || listed(cut, b) {
            continue;
        }
        if sets.join(a, b, record[16] != 0)? == Joined::Conflict {
            unwound.push(a);
        }
    }
    Ok(unwound)
}

impl Winding {
    /// Sums each set's signed volume as it will be written and counts the
    /// sets.
    fn sum(&mut self, triangles: u64, spool: &mut Paged<Spooled>) -> io::Result<()> {
        let mut removed = self.removed.iter().peekable();
        for t in 0..triangles {
            if removed.next_if_eq(&&t).is_some() {
                continue;
            }
            let (root, parity) = self.sets.find(t)?;
            let v = spool.get(t)?.volume6;
            let mut s = self.sums.get(root)?;
            self.components += u64::from(!s.seen);
            s.seen = true;
            s.volume6 += if parity { -v } else { v };
            self.sums.set(root, s)?;
        }
        Ok(())
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A packed normal, unpacked (for other modules' tests).
    pub(crate) fn unpack(packed: u32) -> DVec3 {
        unpack_normal(packed)
    }

    /// Normals pack to within 0.01 degrees, every octant, and zero stays
    /// zero.
    #[test]
    fn normals_pack_closely() {
        let mut state = 17u64;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        for _ in 0..20_000 {
            let n = DVec3::new(next(), next(), next()).normalize_or_zero();
            let back = unpack_normal(pack_normal(n));
            assert!(n.dot(back) > (0.01f64).to_radians().cos(), "{n} -> {back}");
        }
        for n in [DVec3::ZERO, DVec3::NAN, DVec3::new(f64::INFINITY, 0.0, 0.0)] {
            assert_eq!(unpack_normal(pack_normal(n)), DVec3::ZERO);
        }
        assert!(unpack_normal(pack_normal(DVec3::Z)).abs_diff_eq(DVec3::Z, 1e-9));
        assert!(unpack_normal(pack_normal(-DVec3::Z)).abs_diff_eq(-DVec3::Z, 1e-9));
    }

    /// Winds `tris` (corners as store indices into `points`, each vertex
    /// `v` with input id `ids[v]`) through the whole seam side, in the
    /// order `order`; the winding and the triangles written, turned.
    fn wind_all(
        points: &[DVec3],
        ids: &[u64],
        tris: &[[u32; 3]],
        order: &[usize],
    ) -> (Winding, Vec<[u32; 3]>) {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.ply");
        let mut fans = super::super::fans::Fans::new(&path, RunSizes::DEFAULT);
        let mut untwist = Untwist::new(&path).unwrap();
        untwist.add_ids(0, ids).unwrap();
        let mut spool = Paged::new(tempfile::tempfile().unwrap(), 1 << 16);
        for (i, &k) in order.iter().enumerate() {
            let t = tris[k];
            let mut by_id = t;
            by_id.sort_unstable_by_key(|&v| ids[v as usize]);
            let [a, b, c] = by_id.map(|v| points[v as usize]);
            let normal = (b - a).cross(c - a).normalize_or_zero();
            let [p, q, r] = t.map(|v| points[v as usize]);
            let volume6 = p.dot(q.cross(r));
            spool
                .set(
                    i as u64,
                    Spooled {
                        corners: t,
                        volume6,
                    },
                )
                .unwrap();
            fans.add(t, pack_normal(normal)).unwrap();
        }
        let mended = fans
            .mend(|v| Ok(points[v as usize]), |twin| untwist.add(&twin))
            .unwrap();
        let n = order.len() as u64;
        let mut winding = untwist.wind(n, &mended.left_out, &mut spool, None).unwrap();
        let mut written = Vec::new();
        for i in 0..n {
            if listed(&winding.removed, i) {
                continue;
            }
            let mut t = spool.get(i).unwrap().corners;
            if winding.flip(i).unwrap() {
                t.swap(1, 2);
            }
            written.push(t);
        }
        (winding, written)
    }

    /// A Moebius strip of `n` quads (its odd cycle: `2 n` triangles).
    fn moebius(n: u32) -> (Vec<DVec3>, Vec<[u32; 3]>) {
        let m = crate::mesh::shapes::moebius(n);
        (m.vertices, m.triangles)
    }

    /// Input ids equal to the store indices, and the triangles in order.
    fn identity(points: usize, tris: usize) -> (Vec<u64>, Vec<usize>) {
        ((0..points as u64).collect(), (0..tris).collect())
    }

    /// The twist's length follows the set's size, within its bounds.
    #[test]
    fn twist_length_grows_with_the_root_of_the_surface() {
        assert_eq!(twist_steps(0), TWIST_STEPS);
        assert_eq!(twist_steps(3_832), TWIST_STEPS);
        assert_eq!(twist_steps(2_000_000), 353);
        assert_eq!(twist_steps(20_000_000), 1_118.min(MOST_TWIST_STEPS));
        assert_eq!(twist_steps(u32::MAX), MOST_TWIST_STEPS);
    }

    /// A long twist is the surface's own: nothing cut, one set left
    /// non-orientable. A short one (an odd cycle of at most
    /// `TWIST_STEPS` triangles) is cut: what is written is wound
    /// consistently and stays manifold.
    #[test]
    fn long_twists_stay_short_ones_are_cut() {
        let (points, tris) = moebius(40);
        let (ids, order) = identity(points.len(), tris.len());
        let (w, written) = wind_all(&points, &ids, &tris, &order);
        assert_eq!((w.cut, w.non_orientable, w.components), (0, 1, 1));
        assert!(w.unwound >= 1);
        assert_eq!(written.len(), tris.len());
        for n in [4, 10, 25] {
            let (points, tris) = moebius(n);
            let (ids, order) = identity(points.len(), tris.len());
            let (w, written) = wind_all(&points, &ids, &tris, &order);
            assert!(w.cut >= 1, "{n}");
            assert_eq!((w.non_orientable, w.unwound), (0, 0), "{n}");
            let q = crate::mesh::quality(&crate::mesh::Mesh::new(points, written));
            assert!(q.orientable, "{n}: {q}");
            assert_eq!(
                (q.non_manifold_edges, q.non_manifold_vertices),
                (0, 0),
                "{n}"
            );
        }
    }

    /// A closed surface listed with random windings comes out wound
    /// consistently and outward, nothing cut; shuffling the triangles and
    /// renumbering the vertices (the same input ids) changes nothing.
    #[test]
    fn closed_shapes_are_wound_outward_the_same_whatever_the_order() {
        use crate::mesh::shapes::{icosphere, torus};
        for shape in [icosphere(3), torus(2.0, 0.7, 24, 12)] {
            shuffled_shape_is_wound_outward(shape.vertices, shape.triangles);
        }
    }

    fn shuffled_shape_is_wound_outward(points: Vec<DVec3>, mut tris: Vec<[u32; 3]>) {
        let mut state = 5u64;
        let mut next = |n: usize| {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 33) as usize % n
        };
        for t in &mut tris {
            if next(2) == 1 {
                t.swap(0, 1);
            }
        }
        let (ids, order) = identity(points.len(), tris.len());
        let (w, written) = wind_all(&points, &ids, &tris, &order);
        assert_eq!(
            (w.cut, w.unwound, w.non_orientable, w.components),
            (0, 0, 0, 1)
        );
        let mesh = crate::mesh::Mesh::new(points.clone(), written.clone());
        let q = crate::mesh::quality(&mesh);
        assert!(q.orientable);
        let volume: f64 = written
            .iter()
            .map(|t| crate::mesh::volume6(&points, *t, DVec3::ZERO))
            .sum();
        assert!(volume > 0.0, "{volume}");
        // Renumber the vertices (store order) and shuffle the triangles;
        // each vertex keeps its input id.
        let mut relabel: Vec<u32> = (0..points.len() as u32).collect();
        for i in (1..relabel.len()).rev() {
            relabel.swap(i, next(i + 1));
        }
        let mut moved = vec![DVec3::ZERO; points.len()];
        let mut moved_ids = vec![0u64; points.len()];
        for (v, &to) in relabel.iter().enumerate() {
            moved[to as usize] = points[v];
            moved_ids[to as usize] = v as u64;
        }
        let moved_tris: Vec<[u32; 3]> = tris
            .iter()
            .map(|t| t.map(|v| relabel[v as usize]))
            .collect();
        let mut shuffled: Vec<usize> = (0..tris.len()).collect();
        for i in (1..shuffled.len()).rev() {
            shuffled.swap(i, next(i + 1));
        }
        let (_, again) = wind_all(&moved, &moved_ids, &moved_tris, &shuffled);
        let canon = |tris: &[[u32; 3]], id: &dyn Fn(u32) -> u32| {
            let mut out: Vec<[u32; 3]> = tris
                .iter()
                .map(|t| {
                    let t = t.map(id);
                    let k = (0..3).min_by_key(|&k| t[k]).unwrap_or(0);
                    [t[k], t[(k + 1) % 3], t[(k + 2) % 3]]
                })
                .collect();
            out.sort_unstable();
            out
        };
        assert_eq!(
            canon(&written, &|v| v),
            canon(&again, &|v| moved_ids[v as usize] as u32)
        );
    }
}
