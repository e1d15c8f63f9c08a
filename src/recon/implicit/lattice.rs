//! The one global marching-cubes lattice (paper 1 section 2.6, tiled as in
//! ARCHITECTURE.md "Seam policies"): corner positions computed the same way
//! by every tile, and lattice edges packed into `u64` keys so tiles weld their
//! seam vertices exactly.
//!
//! A lattice corner is an integer triple `[i, j, k]`; its position is
//! `origin + [i, j, k] * cell`, evaluated per axis in f64 as
//! `origin.x + (i as f64) * cell` (no fused multiply-add), so two tiles that
//! ask for the same corner get the same bits. A cube is named by its min
//! corner. A lattice edge is named by its lower corner and its axis (0 = x,
//! 1 = y, 2 = z): it joins `corner` and `corner + e_axis`.

use glam::DVec3;

/// Bits of the x and y corner index in an edge key.
pub(crate) const XY_BITS: u32 = 21;
/// Bits of the z corner index in an edge key. One less than x and y because
/// the axis needs 2 bits and 3 x 21 + 2 = 65 does not fit; scans are wider
/// than they are tall, so z gives up the bit.
pub(crate) const Z_BITS: u32 = 20;
/// Smallest and largest x or y corner index an edge key can hold:
/// `[-2^20, 2^20 - 1]`.
pub(crate) const XY_MIN: i64 = -(1 << (XY_BITS - 1));
pub(crate) const XY_MAX: i64 = (1 << (XY_BITS - 1)) - 1;
/// Smallest and largest z corner index an edge key can hold:
/// `[-2^19, 2^19 - 1]`.
pub(crate) const Z_MIN: i64 = -(1 << (Z_BITS - 1));
pub(crate) const Z_MAX: i64 = (1 << (Z_BITS - 1)) - 1;

const AXIS_BITS: u32 = 2;
pub(crate) const Z_SHIFT: u32 = AXIS_BITS;
pub(crate) const Y_SHIFT: u32 = Z_SHIFT + Z_BITS;
pub(crate) const X_SHIFT: u32 = Y_SHIFT + XY_BITS;
const XY_MASK: u64 = (1 << XY_BITS) - 1;
const Z_MASK: u64 = (1 << Z_BITS) - 1;
const AXIS_MASK: u64 = (1 << AXIS_BITS) - 1;

/// Errors of the lattice and marching-cubes layer.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum LatticeError {
    /// The cell size is zero, negative or not finite.
    #[error("lattice cell size must be finite and > 0, got {cell}")]
    BadCellSize {
        /// The size given.
        cell: f64,
    },
    /// The origin has a NaN or infinite coordinate.
    #[error("lattice origin must be finite, got {origin:?}")]
    BadOrigin {
        /// The origin given.
        origin: [f64; 3],
    },
    /// An edge axis other than x (0), y (1) or z (2).
    #[error("edge axis must be 0, 1 or 2, got {axis}")]
    BadAxis {
        /// The axis given.
        axis: u8,
    },
    /// A lattice corner lies outside what an edge key can encode.
    #[error(
        "lattice corner {cell:?} is outside the edge-key range \
         (x, y in [{XY_MIN}, {XY_MAX}], z in [{Z_MIN}, {Z_MAX}])"
    )]
    OutOfRange {
        /// The corner, in lattice cells.
        cell: [i64; 3],
    },
    /// An edge key whose axis bits name no axis.
    #[error("edge key {key:#x} has axis bits 3")]
    BadKey {
        /// The key given.
        key: u64,
    },
    /// The field is NaN or infinite at a cube corner.
    #[error("field value {value} at corner {corner} of cube {cell:?} is not finite")]
    NonFiniteValue {
        /// The cube, by its lowest corner in lattice cells.
        cell: [i64; 3],
        /// The corner (numbering of `mc_table`).
        corner: usize,
        /// The value there.
        value: f64,
    },
    /// The mesh would need more vertices than u32 indices name.
    #[error("mesh has more than u32::MAX vertices")]
    TooManyVertices,
    /// The marching-cubes table could not be built (a bug, not bad input).
    #[error("marching-cubes table construction failed for case {case:#04x}: {reason}")]
    Table {
        /// The cube case (corner sign bits).
        case: usize,
        /// What failed.
        reason: &'static str,
    },
}

/// The global lattice: corner `[i, j, k]` sits at `origin + [i, j, k] * cell`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lattice {
    /// Position of corner `[0, 0, 0]`.
    pub origin: DVec3,
    /// Side of a cube, in the points' units.
    pub cell: f64,
}

impl Lattice {
    /// A lattice with a finite origin and a finite, positive cell size.
    pub fn new(origin: DVec3, cell: f64) -> Result<Self, LatticeError> {
        if !(cell.is_finite() && cell > 0.0) {
            return Err(LatticeError::BadCellSize { cell });
        }
        if !origin.is_finite() {
            return Err(LatticeError::BadOrigin {
                origin: origin.to_array(),
            });
        }
        Ok(Lattice { origin, cell })
    }

    /// Position of lattice corner `c`, bit-identical for every caller.
    pub fn corner(&self, c: [i64; 3]) -> DVec3 {
        DVec3::new(
            self.origin.x + (c[0] as f64) * self.cell,
            self.origin.y + (c[1] as f64) * self.cell,
            self.origin.z + (c[2] as f64) * self.cell,
        )
    }

    /// The cube containing `p` (floor per axis). `p` is expected finite
    /// (coordinates are validated at ingest); a non-finite or huge `p`
    /// saturates to the `i64` range, which [`edge_key`] then rejects.
    pub fn cell_of(&self, p: DVec3) -> [i64; 3] {
        let q = (p - self.origin) / self.cell;
        [q.x.floor() as i64, q.y.floor() as i64, q.z.floor() as i64]
    }
}

/// Whether corner `c` can be packed into an edge key.
pub(crate) fn in_key_range(c: [i64; 3]) -> bool {
    (XY_MIN..=XY_MAX).contains(&c[0])
        && (XY_MIN..=XY_MAX).contains(&c[1])
        && (Z_MIN..=Z_MAX).contains(&c[2])
}

/// Key of the lattice edge from corner `cell` along `axis`.
///
/// Layout, most significant first: x + 2^20 (21 bits), y + 2^20 (21 bits),
/// z + 2^19 (20 bits), axis (2 bits). Keys therefore sort by (x, y, z, axis).
/// Out-of-range corners are an error, never wrapped.
pub fn edge_key(cell: [i64; 3], axis: u8) -> Result<u64, LatticeError> {
    if axis > 2 {
        return Err(LatticeError::BadAxis { axis });
    }
    if !in_key_range(cell) {
        return Err(LatticeError::OutOfRange { cell });
    }
    let x = (cell[0] - XY_MIN) as u64;
    let y = (cell[1] - XY_MIN) as u64;
    let z = (cell[2] - Z_MIN) as u64;
    Ok((x << X_SHIFT) | (y << Y_SHIFT) | (z << Z_SHIFT) | u64::from(axis))
}

/// Inverse of [`edge_key`]: the edge's lower corner and its axis.
pub fn edge_from_key(key: u64) -> Result<([i64; 3], u8), LatticeError> {
    let axis = (key & AXIS_MASK) as u8;
    if axis > 2 {
        return Err(LatticeError::BadKey { key });
    }
    let x = ((key >> X_SHIFT) & XY_MASK) as i64 + XY_MIN;
    let y = ((key >> Y_SHIFT) & XY_MASK) as i64 + XY_MIN;
    let z = ((key >> Z_SHIFT) & Z_MASK) as i64 + Z_MIN;
    Ok(([x, y, z], axis))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn key_round_trips_at_range_ends() {
        for &c in &[
            [0, 0, 0],
            [XY_MIN, XY_MIN, Z_MIN],
            [XY_MAX, XY_MAX, Z_MAX],
            [XY_MIN, XY_MAX, -1],
            [-1, 1, Z_MAX],
        ] {
            for axis in 0..3u8 {
                let key = edge_key(c, axis).unwrap();
                assert_eq!(edge_from_key(key).unwrap(), (c, axis), "{c:?} {axis}");
            }
        }
    }

    #[test]
    fn keys_are_distinct_for_neighbouring_edges() {
        let mut keys = Vec::new();
        for x in -2..2 {
            for y in -2..2 {
                for z in -2..2 {
                    for axis in 0..3u8 {
                        keys.push(edge_key([x, y, z], axis).unwrap());
                    }
                }
            }
        }
        let n = keys.len();
        keys.sort_unstable();
        keys.dedup();
        assert_eq!(keys.len(), n);
    }

    #[test]
    fn out_of_range_is_an_error_not_a_wrap() {
        for &c in &[
            [XY_MAX + 1, 0, 0],
            [XY_MIN - 1, 0, 0],
            [0, XY_MAX + 1, 0],
            [0, 0, Z_MAX + 1],
            [0, 0, Z_MIN - 1],
            [i64::MIN, 0, 0],
        ] {
            assert_eq!(edge_key(c, 0), Err(LatticeError::OutOfRange { cell: c }));
        }
        assert_eq!(edge_key([0; 3], 3), Err(LatticeError::BadAxis { axis: 3 }));
        assert!(matches!(edge_from_key(3), Err(LatticeError::BadKey { .. })));
    }

    #[test]
    fn corner_and_cell_of_agree() {
        let lat = Lattice::new(DVec3::new(1.25, -3.5, 1e5), 0.1).unwrap();
        for &c in &[[0, 0, 0], [-7, 3, 12], [1000, -1000, 5]] {
            let centre = lat.corner(c) + DVec3::splat(0.5 * lat.cell);
            assert_eq!(lat.cell_of(centre), c);
        }
        assert!(Lattice::new(DVec3::ZERO, 0.0).is_err());
        assert!(Lattice::new(DVec3::ZERO, f64::NAN).is_err());
        assert!(Lattice::new(DVec3::new(f64::INFINITY, 0.0, 0.0), 1.0).is_err());
    }
}
