//! The winding tree's leaves, gathered from the store in one pass: each
//! leaf cell's samples summed in fixed point (count, coordinates and their
//! squares relative to the cell, normals), so the sums, and the tree, are
//! the same bits in whatever order the samples come (any tiling, any
//! thread count).
//!
//! A leaf's area is the area its samples cover, from the spread of their
//! coordinates in their plane: uniform samples over a region of area `A`
//! have `A = c sqrt(l1 l2)` for the covariance's two largest eigenvalues,
//! `c = 12` for a square (4 pi for a disc), so the area follows the
//! surface and not the sampling density (Barill et al.'s Voronoi areas do
//! too, but need each sample's neighbours).

use super::{Dipole, WindingTree};
use crate::normals::eigen::sym3_eigen;
use crate::store::{PointStore, StoreError, FLAGS, NORMALS};
use glam::DVec3;
use std::collections::HashMap;

/// Fixed-point units per leaf side for coordinates (16 bits: squares of a
/// billion samples still fit an `i64`) and per unit for normals.
const COORD_ONE: f64 = 65536.0;
const NORMAL_ONE: f64 = 1048576.0;

/// `c` of the module doc: the square's, between the disc's and a
/// triangle's (0.577 L^2 measured for legs L, area 0.5 L^2).
const SPREAD_TO_AREA: f64 = 12.0;

/// Largest area of a leaf in squared sides: a plane's cut through a cube
/// is at most sqrt(2) of a face.
const MAX_LEAF_AREA: f64 = 1.5;

/// Area a sample stands for where its leaf's spread cannot tell, in
/// squared mean spacings: a lone sample has no spread (0.87 spacings^2 a
/// sample on a regular triangular sampling, 4 on a uniformly random one,
/// whose nearest neighbours lie closer). It only seeds the area's
/// fixed-point steps, which leave it for any leaf of two samples or more:
/// the mean spacing is global, and a floor by it would inflate every
/// densely sampled leaf of a scan whose density varies.
const MIN_SAMPLE_AREA: f64 = 0.87;

/// Samples read at a time.
const CHUNK: u64 = 1 << 16;

/// Fixed-point sums of one leaf's samples.
#[derive(Clone, Copy, Debug, Default)]
struct Sums {
    n: u64,
    coords: [i64; 3],
    squares: [i64; 6],
    normals: [i64; 3],
}

/// The leaves being gathered.
pub(crate) struct Gather {
    leaf: f64,
    spacing: f64,
    sums: HashMap<u64, Sums>,
}

impl Gather {
    /// Leaves of side `leaf`; `spacing` is the samples' mean spacing.
    pub(crate) fn new(leaf: f64, spacing: f64) -> Self {
        Gather {
            leaf,
            spacing,
            sums: HashMap::new(),
        }
    }

    /// Adds one sample (relative coordinates) and its unit normal; a
    /// sample outside the codes' range is an error.
    pub(crate) fn add(&mut self, p: DVec3, n: DVec3) -> Result<(), OutOfRange> {
        let cell = (p / self.leaf).floor();
        let code = morton(cell).ok_or(OutOfRange)?;
        let q = (p / self.leaf - cell) * COORD_ONE;
        let q = [q.x as i64, q.y as i64, q.z as i64];
        let s = self.sums.entry(code).or_default();
        s.n += 1;
        for a in 0..3 {
            s.coords[a] += q[a];
            s.normals[a] += (n[a] * NORMAL_ONE) as i64;
        }
        for (k, (a, b)) in PAIRS.iter().enumerate() {
            s.squares[k] += q[*a] * q[*b];
        }
        Ok(())
    }

    /// Leaf cells so far.
    pub(crate) fn len(&self) -> usize {
        self.sums.len()
    }

    /// The tree over the gathered leaves.
    pub(crate) fn tree(self) -> WindingTree {
        let mut leaves: Vec<(u64, Sums)> = self.sums.into_iter().collect();
        leaves.sort_unstable_by_key(|l| l.0);
        let (leaf, spacing) = (self.leaf, self.spacing);
        let dipoles = leaves
            .into_iter()
            .map(|(code, s)| (code, dipole(&s, code, leaf, spacing)))
            .collect();
        WindingTree::new(leaf, dipoles)
    }
}

/// A sample beyond the range of leaf codes.
#[derive(Clone, Copy, Debug)]
pub(crate) struct OutOfRange;

/// The (row, column) of each stored second moment.
const PAIRS: [(usize, usize); 6] = [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)];

/// One leaf's dipole from its sums.
fn dipole(s: &Sums, code: u64, leaf: f64, spacing: f64) -> Dipole {
    let n = s.n as f64;
    let mean = s.coords.map(|c| c as f64 / COORD_ONE / n);
    let mut cov = [[0.0; 3]; 3];
    for (k, (a, b)) in PAIRS.iter().enumerate() {
        let m = s.squares[k] as f64 / (COORD_ONE * COORD_ONE) / n - mean[*a] * mean[*b];
        cov[*a][*b] = m;
        cov[*b][*a] = m;
    }
    let (l, _) = sym3_eigen(cov);
    let least = n * MIN_SAMPLE_AREA * (spacing / leaf).powi(2);
    let seed = least.min(MAX_LEAF_AREA);
    let area = covered_area(l[2].max(0.0), l[1].max(0.0), n, seed).min(MAX_LEAF_AREA) * leaf * leaf;
    let normal = DVec3::from_array(s.normals.map(|v| v as f64 / NORMAL_ONE)) / n;
    let corner = unmorton(code) * leaf;
    Dipole::leaf(corner + DVec3::from_array(mean) * leaf, normal * area, area)
}

/// The area (in squared sides) that `n` samples whose spread in their
/// plane has variances `l1`, `l2` cover: each sample stands for a patch
/// of `A / n`, whose own variance `A / 12 n` the samples' spread lacks (a
/// row of samples `s` apart spans `W - s`, not `W`), so `A` solves
/// `A = c sqrt((l1 + A / 12n)(l2 + A / 12n))`, by a few fixed-point steps
/// from at least `seed` (each shrinks the error `n` times; from 0, two
/// samples, whose spread has no width, would stay at 0).
fn covered_area(l1: f64, l2: f64, n: f64, seed: f64) -> f64 {
    let mut area = (SPREAD_TO_AREA * (l1 * l2).sqrt()).max(seed);
    for _ in 0..AREA_STEPS {
        let own = area / (SPREAD_TO_AREA * n);
        area = SPREAD_TO_AREA * ((l1 + own) * (l2 + own)).sqrt();
    }
    area
}

/// Fixed-point steps of [`covered_area`].
const AREA_STEPS: usize = 8;

/// Bias that makes a cell index non-negative, and the bits each takes.
const BIAS: i64 = 1 << 20;
const BITS: u32 = 21;

/// The Morton code of cell `c` (integral coordinates), interleaving x, y
/// and z bits; `None` beyond 21 bits an axis.
pub(crate) fn morton(c: DVec3) -> Option<u64> {
    let mut code = 0u64;
    for a in 0..3 {
        let v = c[a] as i64 + BIAS;
        if !(0..1 << BITS).contains(&v) || !c[a].is_finite() {
            return None;
        }
        code |= spread_bits(v as u64) << a;
    }
    Some(code)
}

fn spread_bits(v: u64) -> u64 {
    (0..BITS).fold(0, |acc, b| acc | (((v >> b) & 1) << (3 * b)))
}

/// The cell whose code is `code` (its min corner in cells).
fn unmorton(code: u64) -> DVec3 {
    let mut c = DVec3::ZERO;
    for a in 0..3usize {
        let v = (0..BITS).fold(0u64, |acc, b| {
            acc | (((code >> (3 * b + a as u32)) & 1) << b)
        });
        c[a] = (v as i64 - BIAS) as f64;
    }
    c
}

/// Most leaves a tree holds: a finer tree of a larger scan is gathered
/// again with leaves twice the side, so the tree's memory is bounded
/// whatever the point count ([`MAX_TREE_BYTES`]).
pub(crate) const MAX_LEAVES: usize = 400_000;

/// Bytes the tree holds at most: its leaves and the levels above them (a
/// third as many again on a surface, each level a quarter of the one
/// below).
pub(crate) const MAX_TREE_BYTES: u64 = (MAX_LEAVES as u64 * 4 / 3 + 8) * 64;

/// The winding tree of `store`'s samples whose flags have none of
/// `unusable`'s bits and whose normal is not zero, in leaves of side
/// `leaf` or, when those would be more than [`MAX_LEAVES`], the least
/// multiple of it by a power of two that are not. A sample beyond the
/// leaf codes' range is refused.
pub(crate) fn gather_store(
    store: &PointStore,
    leaf: f64,
    spacing: f64,
    unusable: u8,
) -> Result<WindingTree, StoreError> {
    let mut side = leaf;
    loop {
        if let Some(gather) = gather_within(store, side, spacing, unusable)? {
            return Ok(gather.tree());
        }
        side *= 2.0;
    }
}

/// One pass over the store in leaves of side `leaf`; `None` as soon as
/// they outnumber [`MAX_LEAVES`].
fn gather_within(
    store: &PointStore,
    leaf: f64,
    spacing: f64,
    unusable: u8,
) -> Result<Option<Gather>, StoreError> {
    let (normals, flags) = (store.column(&NORMALS)?, store.column(&FLAGS)?);
    let mut gather = Gather::new(leaf, spacing);
    let (mut pts, mut nrm, mut flg) = (Vec::new(), Vec::new(), Vec::new());
    for at in (0..store.len()).step_by(CHUNK as usize) {
        let count = CHUNK.min(store.len() - at);
        store.read_points(at, count, &mut pts)?;
        normals.read_f32(at, count, &mut nrm)?;
        flags.read_u8(at, count, &mut flg)?;
        for (i, p) in pts.iter().enumerate() {
            let n = crate::normals::normal_at(&nrm, i);
            if flg[i] & unusable != 0 || n == DVec3::ZERO {
                continue;
            }
            gather.add(*p, n).map_err(|_| StoreError::Corrupt {
                path: store.dir().to_path_buf(),
                reason: format!("point {p} lies beyond the winding tree's range"),
            })?;
        }
        if gather.len() > MAX_LEAVES {
            return Ok(None);
        }
    }
    Ok(Some(gather))
}
