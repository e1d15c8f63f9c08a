//! Lattice cubes and corners as sorted `u64` keys: a corner's key, the
//! eight corners of a cube, the cubes holding samples, which tile owns a
//! cube, and the forward cursor that reads the corner values of cubes
//! visited in key order (the marching loop's and the surface walk's).

use super::blocks::{block_of, BLOCK};
use super::lattice::{edge_from_key, edge_key, Lattice, LatticeError};
use super::refine::CornerValue;
use super::sdf::Known;
use crate::geom::Aabb;
use crate::pipeline::KernelError;
use glam::DVec3;
use rayon::prelude::*;

/// A corner as a `u64` that sorts like the triple: its x-edge key, which
/// the stitcher needs anyway, so a corner out of key range is refused here.
/// Sorting keys rather than triples is several times faster.
pub(crate) fn corner_key(c: [i64; 3]) -> Result<u64, LatticeError> {
    edge_key(c, 0)
}

pub(crate) fn corner_of(key: u64) -> [i64; 3] {
    // Keys come from `corner_key`, so decoding cannot fail.
    edge_from_key(key).map_or([0; 3], |(c, _)| c)
}

pub(crate) const CORNERS: [[i64; 3]; 8] = [
    [0, 0, 0],
    [1, 0, 0],
    [0, 1, 0],
    [1, 1, 0],
    [0, 0, 1],
    [1, 0, 1],
    [0, 1, 1],
    [1, 1, 1],
];

/// Cubes per parallel task of the marching loop.
pub(crate) const CUBES_PER_TASK: usize = 4096;

/// Reads the corner values of cubes visited in increasing order. Corner
/// keys order like (x, y, z) triples, so for each of the eight corner
/// offsets the keys of successive cubes' corners increase too: eight
/// cursors that only move forward replace eight binary searches per cube
/// (most of the marching loop's time, in cache misses).
pub(crate) struct CornerCursor<'a> {
    corners: &'a [CornerValue],
    at: [usize; 8],
    /// Every cube with all corners defined is drawn (`--closed`), not
    /// only those with a corner on the data.
    everywhere: bool,
}

impl<'a> CornerCursor<'a> {
    /// Cursors placed for cubes from `first` on.
    pub(crate) fn new(
        corners: &'a [CornerValue],
        first: [i64; 3],
        everywhere: bool,
    ) -> Result<Self, KernelError> {
        let keys = corner_keys(first)?;
        Ok(CornerCursor {
            corners,
            at: keys.map(|key| corners.partition_point(|e| e.0 < key)),
            everywhere,
        })
    }

    /// The values at the corners of `cube` (no earlier than the last cube
    /// asked), in [`CORNERS`] order, or `None` if one is undefined or none
    /// projects onto the data.
    /// With the values, whether the winding number gave one of them (the
    /// cube lies away from the data, `--closed`).
    pub(crate) fn values(
        &mut self,
        cube: [i64; 3],
    ) -> Result<Option<([f64; 8], bool)>, KernelError> {
        let keys = corner_keys(cube)?;
        let mut values = [0.0; 8];
        let (mut on_data, mut away) = (false, false);
        for ((at, key), value) in self.at.iter_mut().zip(keys).zip(values.iter_mut()) {
            *at = seek(self.corners, *at, key);
            match self.corners.get(*at) {
                Some(&(k, Some(known))) if k == key => {
                    on_data |= matches!(known, Known::OnData(..));
                    away |= matches!(known, Known::Winding(_));
                    *value = known.value();
                }
                _ => return Ok(None),
            }
        }
        Ok((on_data || self.everywhere).then_some((values, away)))
    }
}

/// The first index from `at` on whose key is not below `key`: a few steps
/// forward, then a bisection, so a cursor crossing a long run of corners
/// (the walk's sparse frontiers) does not step through it one by one.
fn seek(corners: &[CornerValue], at: usize, key: u64) -> usize {
    let near = corners.len().min(at + 8);
    match corners[at.min(near)..near].iter().position(|e| e.0 >= key) {
        Some(i) => at + i,
        None => near + corners[near..].partition_point(|e| e.0 < key),
    }
}

fn corner_keys(cube: [i64; 3]) -> Result<[u64; 8], KernelError> {
    let mut keys = [0; 8];
    for (key, o) in keys.iter_mut().zip(CORNERS) {
        *key = corner_key([cube[0] + o[0], cube[1] + o[1], cube[2] + o[2]])
            .map_err(KernelError::failed)?;
    }
    Ok(keys)
}

/// Whether the tile with core box `core` owns `cube`: the min corner of
/// its block ([`super::blocks`]) lies in the core, half-open, so the cores'
/// owned blocks partition the lattice and a block is one tile's whole.
pub fn owns(lattice: &Lattice, core: &Aabb, cube: [i64; 3]) -> bool {
    let p = lattice.corner(block_of(cube).map(|b| b * BLOCK));
    (0..3).all(|a| core.min[a] <= p[a] && p[a] < core.max[a])
}

/// Index bound far beyond any key (keys hold 21 bits an axis).
const FAR: f64 = (1u64 << 40) as f64;

/// Cube index bounds (inclusive) holding every cube within `pad` cubes of
/// one the tile with core `core` owns ([`owned_cubes`]), and one more: a
/// little wider is harmless, narrower is not.
pub(crate) fn cube_range(lattice: &Lattice, core: &Aabb, pad: i64) -> [[i64; 2]; 3] {
    let (lo, hi) = owned_cubes(lattice, core);
    std::array::from_fn(|a| [lo[a] - pad - 1, hi[a] + pad])
}

pub(crate) fn inside(region: &[[i64; 2]; 3], c: [i64; 3]) -> bool {
    (0..3).all(|a| region[a][0] <= c[a] && c[a] <= region[a][1])
}

/// The cubes [`owns`] gives the tile with core box `core`, as inclusive
/// index bounds per axis (an empty axis has lower > upper): the test is one
/// comparison per axis, so its cubes form a box.
pub(crate) fn owned_range(lattice: &Lattice, core: &Aabb) -> [[i64; 2]; 3] {
    let (lo, hi) = owned_cubes(lattice, core);
    std::array::from_fn(|a| [lo[a], hi[a] - 1])
}

/// The owned cubes as half-open index ranges `[lo, hi)` per axis (huge
/// values standing for an infinite core side): the blocks whose first
/// cube's min corner lies in the core, by the comparisons [`owns`] makes.
pub(crate) fn owned_cubes(lattice: &Lattice, core: &Aabb) -> ([i64; 3], [i64; 3]) {
    let first = |v: f64, a: usize| -> i64 {
        if v == f64::NEG_INFINITY {
            return i64::MIN / 4;
        }
        if v == f64::INFINITY {
            return i64::MAX / 4;
        }
        // The first cube whose min corner is >= v.
        let mut i = ((v - lattice.origin[a]) / lattice.cell)
            .floor()
            .clamp(-FAR, FAR) as i64;
        while lattice.corner([i, i, i])[a] < v {
            i += 1;
        }
        while lattice.corner([i - 1, i - 1, i - 1])[a] >= v {
            i -= 1;
        }
        // The first block starting there or after.
        (i + BLOCK - 1).div_euclid(BLOCK) * BLOCK
    };
    let lo = [0, 1, 2].map(|a| first(core.min[a], a));
    let hi = [0, 1, 2].map(|a| first(core.max[a], a));
    (lo, hi)
}

/// The cubes holding a sample, sorted keys.
pub(crate) fn occupied(lattice: &Lattice, points: &[DVec3]) -> Result<Vec<u64>, KernelError> {
    let mut occupied = points
        .iter()
        .map(|p| corner_key(lattice.cell_of(*p)))
        .collect::<Result<Vec<u64>, _>>()
        .map_err(KernelError::failed)?;
    // Points come in space-filling order: most neighbours share a cube.
    occupied.dedup();
    occupied.par_sort_unstable();
    occupied.dedup();
    Ok(occupied)
}
