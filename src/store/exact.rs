//! The input's coordinates exactly as read, in input order (`xyz.input`):
//! what every output that carries the input's points writes. The tile
//! columns keep f32 offsets from the origin for the kernels (half the
//! bytes, and enough for a neighbourhood's geometry), but an f32 offset
//! moves a point by up to half its last place: 3.9 mm across a
//! 200 km UTM extent. So the first read keeps the coordinates beside the
//! attributes (input order, sequential appends), and the later build passes
//! read them back from here instead of from a spill of their own.
//!
//! Two encodings ([`Coordinates`]): f64 (24 bytes a point), or for a LAS
//! input the record's own integers under its scale and offset (12 bytes),
//! decoded as the `las` crate decodes them, `scale * i + offset`, so the
//! f64 is the reader's bit for bit and a LAS written with the same scale
//! and offset holds the same integers.

use super::{Column, PointStore, StoreError};
use crate::io::LasTransform;
use glam::DVec3;
use serde::{Deserialize, Serialize};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// File name of the exact coordinates, in input order.
pub(crate) const EXACT_FILE: &str = "xyz.input";

/// How `xyz.input` holds a point.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Coordinates {
    /// Three little-endian f64.
    F64,
    /// Three little-endian i32 of a LAS grid: `x = scale * i + offset`.
    LasGrid {
        /// Size of one integer step, per axis.
        scale: [f64; 3],
        /// Coordinate of integer 0, per axis.
        offset: [f64; 3],
    },
}

impl Coordinates {
    /// The encoding for an input with this LAS transform (if it has one).
    /// A LAS header whose scale is not a positive number (a broken file
    /// the reader still decodes) keeps f64.
    pub(crate) fn for_input(las: Option<LasTransform>) -> Self {
        let usable = |t: &LasTransform| {
            t.scale.is_finite() && t.scale.min_element() > 0.0 && t.offset.is_finite()
        };
        match las.filter(usable) {
            Some(t) => Coordinates::LasGrid {
                scale: t.scale.to_array(),
                offset: t.offset.to_array(),
            },
            None => Coordinates::F64,
        }
    }

    /// Bytes of one point.
    pub(crate) fn item_bytes(self) -> usize {
        match self {
            Coordinates::F64 => 24,
            Coordinates::LasGrid { .. } => 12,
        }
    }

    /// The LAS transform of a LAS grid (what a LAS output reuses).
    pub fn las_transform(self) -> Option<LasTransform> {
        match self {
            Coordinates::F64 => None,
            Coordinates::LasGrid { scale, offset } => Some(LasTransform {
                scale: DVec3::from_array(scale),
                offset: DVec3::from_array(offset),
            }),
        }
    }

    /// Appends `p`'s encoding to `out`; `None` when `p` is not on the grid
    /// (a LAS reader gave a coordinate its integers do not make).
    pub(super) fn encode(self, p: DVec3, out: &mut Vec<u8>) -> Option<()> {
        match self {
            Coordinates::F64 => p
                .to_array()
                .iter()
                .for_each(|v| out.extend(v.to_le_bytes())),
            Coordinates::LasGrid { scale, offset } => {
                for a in 0..3 {
                    let q = ((p[a] - offset[a]) / scale[a]).round();
                    let fits = q >= f64::from(i32::MIN) && q <= f64::from(i32::MAX);
                    let i = q as i32;
                    if !fits || grid_value(scale[a], offset[a], i) != p[a] {
                        return None;
                    }
                    out.extend(i.to_le_bytes());
                }
            }
        }
        Some(())
    }

    /// Decodes the points of `bytes` (whole items) onto the end of `out`.
    pub(crate) fn decode(self, bytes: &[u8], out: &mut Vec<DVec3>) {
        match self {
            Coordinates::F64 => out.extend(bytes.chunks_exact(24).map(|r| {
                let v = |o: usize| f64::from_le_bytes(take8(&r[o..]));
                DVec3::new(v(0), v(8), v(16))
            })),
            Coordinates::LasGrid { scale, offset } => out.extend(bytes.chunks_exact(12).map(|r| {
                let v = |a: usize| {
                    let i =
                        i32::from_le_bytes([r[4 * a], r[4 * a + 1], r[4 * a + 2], r[4 * a + 3]]);
                    grid_value(scale[a], offset[a], i)
                };
                DVec3::new(v(0), v(1), v(2))
            })),
        }
    }
}

/// A LAS integer's coordinate, computed as the `las` crate computes it.
fn grid_value(scale: f64, offset: f64, i: i32) -> f64 {
    scale * f64::from(i) + offset
}

fn take8(b: &[u8]) -> [u8; 8] {
    [b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]]
}

/// Appends the input's coordinates to `xyz.input` as its chunks arrive.
pub(super) struct ExactSink {
    coordinates: Coordinates,
    path: PathBuf,
    out: BufWriter<File>,
    bytes: Vec<u8>,
    written: u64,
}

impl ExactSink {
    pub fn create(dir: &Path, coordinates: Coordinates) -> Result<Self, StoreError> {
        let path = dir.join(EXACT_FILE);
        let file = File::create(&path).map_err(|e| StoreError::os(&path, e))?;
        Ok(ExactSink {
            coordinates,
            out: BufWriter::with_capacity(1 << 20, file),
            path,
            bytes: Vec::new(),
            written: 0,
        })
    }

    /// Appends `pts` (the next points in input order).
    pub fn write(&mut self, pts: &[DVec3]) -> Result<(), StoreError> {
        self.bytes.clear();
        for (k, p) in pts.iter().enumerate() {
            if self.coordinates.encode(*p, &mut self.bytes).is_none() {
                return Err(StoreError::Corrupt {
                    path: self.path.clone(),
                    reason: format!(
                        "point {} ({p}) is not on the input's LAS grid {:?}",
                        self.written + k as u64,
                        self.coordinates
                    ),
                });
            }
        }
        self.written += pts.len() as u64;
        self.out
            .write_all(&self.bytes)
            .map_err(|e| StoreError::os(&self.path, e))
    }

    pub fn finish(self) -> Result<(), StoreError> {
        let path = self.path;
        self.out
            .into_inner()
            .map_err(|e| StoreError::os(&path, e.into_error()))?;
        Ok(())
    }
}

/// Calls `f(first, points)` for consecutive chunks of `chunk` points of the
/// exact column at `dir`, in input order (the build's later passes).
pub(super) fn for_each_exact(
    dir: &Path,
    coordinates: Coordinates,
    count: u64,
    chunk: u64,
    mut f: impl FnMut(u64, &[DVec3]) -> Result<(), StoreError>,
) -> Result<(), StoreError> {
    let column = Column::open(&dir.join(EXACT_FILE), coordinates.item_bytes(), false)?;
    let mut pts = Vec::with_capacity(chunk as usize);
    let mut done = 0;
    while done < count {
        let n = (count - done).min(chunk.max(1));
        pts.clear();
        column.with_bytes(done, n, |b| coordinates.decode(b, &mut pts))?;
        f(done, &pts)?;
        done += n;
    }
    Ok(())
}

/// Items between two wanted ones up to which a gather reads them along
/// rather than starting a new read.
const GATHER_GAP: u64 = 32;

impl PointStore {
    /// How the store keeps the input's exact coordinates.
    pub fn coordinates(&self) -> Coordinates {
        self.manifest.coordinates
    }

    /// The input's coordinates, exactly as read, of the points of
    /// input-order ranks `[first, first + count)`, into `out`.
    pub fn read_exact(
        &self,
        first: u64,
        count: u64,
        out: &mut Vec<DVec3>,
    ) -> Result<(), StoreError> {
        out.clear();
        self.keeps_input(false)?;
        let c = self.coordinates();
        let column = Column::open(&self.dir.join(EXACT_FILE), c.item_bytes(), false)?;
        column.with_bytes(first, count, |b| c.decode(b, out))
    }
}

impl PointStore {
    /// The input's exact coordinates of the points of *store* range
    /// `[first, first + count)` (a tile's), in store order: what a mesh
    /// whose vertices are the input's points writes. Their input ranks are
    /// scattered through the input-order column, so they are read sorted,
    /// in runs of positioned reads (nearby ranks share one), never by
    /// mapping the column: a map's touched pages would count in RSS.
    pub fn read_exact_in_store_order(
        &self,
        first: u64,
        count: u64,
        out: &mut Vec<DVec3>,
    ) -> Result<(), StoreError> {
        self.keeps_input(false)?;
        let mut ranks = Vec::new();
        self.read_indices(first, count, &mut ranks)?;
        let mut order: Vec<usize> = (0..ranks.len()).collect();
        order.sort_unstable_by_key(|&k| ranks[k]);
        let c = self.coordinates();
        let bytes = c.item_bytes();
        let column = Column::open(&self.dir.join(EXACT_FILE), bytes, false)?;
        out.clear();
        out.resize(ranks.len(), DVec3::ZERO);
        let (mut buf, mut one) = (Vec::new(), Vec::with_capacity(1));
        let mut k = 0;
        while k < order.len() {
            let start = ranks[order[k]];
            let mut end = k + 1;
            while end < order.len() && ranks[order[end]] - ranks[order[end - 1]] <= GATHER_GAP {
                end += 1;
            }
            let span = ranks[order[end - 1]] - start + 1;
            column.read_items(start, span, &mut buf)?;
            for &slot in &order[k..end] {
                let at = (ranks[slot] - start) as usize * bytes;
                one.clear();
                c.decode(&buf[at..at + bytes], &mut one);
                out[slot] = one[0];
            }
            k = end;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn both_encodings_give_back_the_same_f64() {
        let mut rng = crate::rng::Rng::new(3);
        let grid = Coordinates::LasGrid {
            scale: [0.001, 0.001, 0.01],
            offset: [431_000.0, 5_218_000.0, 0.0],
        };
        for c in [Coordinates::F64, grid] {
            let pts: Vec<DVec3> = (0..1000)
                .map(|_| {
                    let i = [0; 3].map(|_| rng.below(400_000_000) as i32 - 200_000_000);
                    match c {
                        Coordinates::F64 => DVec3::new(
                            4.0e5 + rng.uniform() * 2.0e5,
                            5.0e6 + rng.uniform() * 2.0e5,
                            rng.uniform() * 1e3,
                        ),
                        Coordinates::LasGrid { scale, offset } => DVec3::new(
                            grid_value(scale[0], offset[0], i[0]),
                            grid_value(scale[1], offset[1], i[1]),
                            grid_value(scale[2], offset[2], i[2]),
                        ),
                    }
                })
                .collect();
            let mut bytes = Vec::new();
            for p in &pts {
                c.encode(*p, &mut bytes).unwrap();
            }
            assert_eq!(bytes.len(), pts.len() * c.item_bytes());
            let mut back = Vec::new();
            c.decode(&bytes, &mut back);
            assert_eq!(back, pts, "{c:?}");
        }
    }

    #[test]
    fn a_point_off_the_grid_is_not_encoded() {
        let grid = Coordinates::LasGrid {
            scale: [0.01; 3],
            offset: [0.0; 3],
        };
        let mut bytes = Vec::new();
        assert!(grid
            .encode(DVec3::new(0.005, 0.0, 0.0), &mut bytes)
            .is_none());
        assert!(grid
            .encode(DVec3::new(1e12, 0.0, 0.0), &mut bytes)
            .is_none());
    }
}
