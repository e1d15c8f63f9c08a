//! Exact kNN over a uniform grid of cubes (paper 1 section 2.1).
//!
//! Storage is compact: the points are sorted by cell (z, then y, then x, then
//! index) into one array; each occupied cell keeps its x and its start offset;
//! each occupied row of cells (fixed y, z) is found through a small
//! open-addressing table, so a run of cells along x is one contiguous range.
//!
//! Deviations from the paper, with reasons:
//! - The paper searches the fixed 27 cubes around the query, which is not exact
//!   (PITFALLS.md "Neighbourhoods"). We start with those 27 and widen ring by
//!   ring until the k-th distance is inside the searched block.
//! - The paper addresses cubes by a hash of (ix, iy, iz); we hash rows, so one
//!   lookup serves a whole run of cells along x.
//! - The cell size is chosen from the data (see [`GridIndex::new`]) rather than
//!   from the marching-cube edge, which this stage does not know.
//! - If the search would probe more rows than there are points (at least
//!   4096; a query far outside the data, or cells far too small), it scans all
//!   points instead: same answer, cost bounded by O(n) per query.

use glam::DVec3;
use rayon::prelude::*;

use super::brute::{dist2, neighbour_order};
use super::{check_input, IndexError, KnnIndex, Neighbour};
use crate::geom::Aabb;

/// Wanted mean number of points per occupied cell. About four points per
/// cell on a surface puts the 12th neighbour inside the first 27 cells for
/// most queries while keeping the cells scanned few (measured in benches/knn.rs).
const TARGET_PER_CELL: f64 = 4.0;
/// Cells per axis are capped so that row keys fit easily in a u64.
const MAX_CELLS_PER_AXIS: f64 = (1u64 << 21) as f64;
/// Query cells are clamped to this range before the cast to i64.
const FAR_CELL: f64 = (1u64 << 40) as f64;

/// Uniform-grid exact kNN index over borrowed points.
pub struct GridIndex<'a> {
    tie: &'a [u64],
    origin: DVec3,
    cell: f64,
    inv_cell: f64,
    dims: [i64; 3],
    /// Points in cell order, with `ids[j]` the original index of `sorted[j]`.
    sorted: Vec<DVec3>,
    ids: Vec<u32>,
    /// Per occupied cell, in storage order: its x, and where its points start
    /// (`cell_start` has one extra entry, the total).
    cell_x: Vec<u32>,
    cell_start: Vec<u32>,
    rows: RowTable,
    /// Scale of the coordinates, for the rounding allowance of the stop test.
    coord_scale: f64,
}

impl<'a> GridIndex<'a> {
    /// Builds the grid with an automatic cell size.
    ///
    /// Rule: the points are assumed to sample a surface spanning the bounding
    /// box, of area about `A = xy + yz + zx` (half the box's surface area: exact
    /// for a flat sheet, 5 % low for a sphere). The cell edge `sqrt(T A / n)`
    /// puts about `T` = 4 points in a cell the surface crosses. The mean
    /// occupancy of the resulting grid is then measured; if it is off by more
    /// than 4x (volumetric clouds, clusters), the edge is rescaled by
    /// `sqrt(T / mean)` and the grid rebuilt, at most twice.
    pub fn new(points: &'a [DVec3], tie: &'a [u64]) -> Result<Self, IndexError> {
        check_input(points, tie)?;
        let bbox = bounding_box(points);
        let mut cell = surface_cell_guess(bbox.extent(), points.len());
        let mut grid = Self::build(points, tie, &bbox, cell);
        for _ in 0..2 {
            let mean = points.len() as f64 / grid.cell_x.len().max(1) as f64;
            if (TARGET_PER_CELL / 4.0..=TARGET_PER_CELL * 4.0).contains(&mean) {
                break;
            }
            cell *= (TARGET_PER_CELL / mean).sqrt();
            grid = Self::build(points, tie, &bbox, cell);
        }
        Ok(grid)
    }

    /// Builds the grid with cells of edge `cell` (grown if the grid would need
    /// more than 2^21 cells along an axis).
    pub fn with_cell(points: &'a [DVec3], tie: &'a [u64], cell: f64) -> Result<Self, IndexError> {
        check_input(points, tie)?;
        if !(cell.is_finite() && cell > 0.0) {
            return Err(IndexError::BadCellSize { cell });
        }
        Ok(Self::build(points, tie, &bounding_box(points), cell))
    }

    /// The cell edge in use.
    pub fn cell_size(&self) -> f64 {
        self.cell
    }

    /// Number of occupied cells.
    pub fn occupied_cells(&self) -> usize {
        self.cell_x.len()
    }

    fn build(points: &'a [DVec3], tie: &'a [u64], bbox: &Aabb, cell: f64) -> Self {
        let extent = bbox.extent();
        let cell = cell.max(extent.max_element() / (MAX_CELLS_PER_AXIS - 1.0));
        let origin = if bbox.is_empty() {
            DVec3::ZERO
        } else {
            bbox.min
        };
        let inv_cell = 1.0 / cell;
        let dims = extent
            .to_array()
            .map(|e| ((e * inv_cell).floor() as i64 + 1).clamp(1, MAX_CELLS_PER_AXIS as i64));
        let cell_of = |p: &DVec3| {
            let t = ((*p - origin) * inv_cell).floor().to_array();
            let c: [i64; 3] = std::array::from_fn(|a| (t[a] as i64).clamp(0, dims[a] - 1));
            (row_key(c[1], c[2], dims), c[0] as u32)
        };
        let mut keys: Vec<(u64, u32, u32)> = points
            .par_iter()
            .zip(0..points.len() as u32)
            .map(|(p, i)| {
                let (row, x) = cell_of(p);
                (row, x, i)
            })
            .collect();
        keys.par_sort_unstable();
        let mut grid = GridIndex {
            tie,
            origin,
            cell,
            inv_cell,
            dims,
            sorted: keys.iter().map(|k| points[k.2 as usize]).collect(),
            ids: keys.iter().map(|k| k.2).collect(),
            cell_x: Vec::new(),
            cell_start: Vec::new(),
            rows: RowTable::default(),
            coord_scale: origin.abs().max_element() + extent.max_element() + cell,
        };
        grid.index_cells(&keys);
        grid
    }

    /// Fills the cell and row tables from the sorted (row, x, index) keys.
    fn index_cells(&mut self, keys: &[(u64, u32, u32)]) {
        let mut rows: Vec<(u64, u32, u32)> = Vec::new();
        let mut prev: Option<(u64, u32)> = None;
        for (j, &(row, x, _)) in keys.iter().enumerate() {
            if prev == Some((row, x)) {
                continue;
            }
            let cell = self.cell_x.len() as u32;
            match rows.last_mut() {
                Some(last) if last.0 == row => last.2 = cell + 1,
                _ => rows.push((row, cell, cell + 1)),
            }
            self.cell_x.push(x);
            self.cell_start.push(j as u32);
            prev = Some((row, x));
        }
        self.cell_start.push(keys.len() as u32);
        self.rows = RowTable::new(&rows);
    }

    /// The cell containing `q`, unclamped (queries may lie outside the grid).
    fn query_cell(&self, q: DVec3) -> [i64; 3] {
        let t = ((q - self.origin) * self.inv_cell).floor().to_array();
        t.map(|v| v.clamp(-FAR_CELL, FAR_CELL) as i64)
    }

    /// Chebyshev distance, in cells, from cell `c` to the grid.
    fn cells_to_grid(&self, c: [i64; 3]) -> i64 {
        (0..3)
            .map(|a| (-c[a]).max(c[a] - (self.dims[a] - 1)).max(0))
            .max()
            .unwrap_or(0)
    }

    fn block_covers_grid(&self, c: [i64; 3], r: i64) -> bool {
        (0..3).all(|a| c[a] - r <= 0 && c[a] + r >= self.dims[a] - 1)
    }

    /// Exactness test: every point outside the block of radius `r` around
    /// cell `c` is farther than the k-th candidate. Sides of the block beyond
    /// the grid hold no points and do not limit the margin. The margin is
    /// shrunk by a rounding allowance for the cell assignment and box corners.
    fn settled(&self, q: DVec3, c: [i64; 3], r: i64, kth_dist2: f64) -> bool {
        let (qa, oa) = (q.to_array(), self.origin.to_array());
        let mut margin = f64::INFINITY;
        for a in 0..3 {
            if c[a] - r > 0 {
                margin = margin.min(qa[a] - (oa[a] + (c[a] - r) as f64 * self.cell));
            }
            if c[a] + r < self.dims[a] - 1 {
                margin = margin.min(oa[a] + (c[a] + r + 1) as f64 * self.cell - qa[a]);
            }
        }
        let scale = self.coord_scale + (q - self.origin).abs().max_element();
        let allowance = 16.0 * f64::EPSILON * scale;
        kth_dist2.sqrt() * (1.0 + 8.0 * f64::EPSILON) + allowance < margin
    }

    /// Scans the cells at Chebyshev distance in `(inner, r]` from cell `c`
    /// (`inner = -1` scans the whole block).
    fn scan_shell(&self, s: &mut Search<'_>, c: [i64; 3], inner: i64, r: i64) {
        let span = |a: usize| ((c[a] - r).max(0), (c[a] + r).min(self.dims[a] - 1));
        let ((y0, y1), (z0, z1), (x0, x1)) = (span(1), span(2), span(0));
        for z in z0..=z1 {
            for y in y0..=y1 {
                let inside = (y - c[1]).abs() <= inner && (z - c[2]).abs() <= inner;
                let Some(row) = self.rows.get(row_key(y, z, self.dims)) else {
                    continue;
                };
                if inside {
                    self.scan_cells(s, row, x0, x1.min(c[0] - inner - 1));
                    self.scan_cells(s, row, x0.max(c[0] + inner + 1), x1);
                } else {
                    self.scan_cells(s, row, x0, x1);
                }
            }
        }
    }

    /// Rows of the grid a block of radius `r` around cell `c` touches: the
    /// row lookups a shell scan of that block costs at most.
    fn rows_in_block(&self, c: [i64; 3], r: i64) -> usize {
        let span = |a: usize| ((c[a] + r).min(self.dims[a] - 1) - (c[a] - r).max(0) + 1).max(0);
        (span(1) as usize).saturating_mul(span(2) as usize)
    }

    /// Offers the points of the row's cells with x in `[x0, x1]`.
    fn scan_cells(&self, s: &mut Search<'_>, row: (u32, u32), x0: i64, x1: i64) {
        if x0 > x1 {
            return;
        }
        let cells = &self.cell_x[row.0 as usize..row.1 as usize];
        let a = row.0 as usize + cells.partition_point(|&x| (x as i64) < x0);
        let b = row.0 as usize + cells.partition_point(|&x| (x as i64) <= x1);
        if a < b {
            let (from, to) = (self.cell_start[a] as usize, self.cell_start[b] as usize);
            self.scan_points(s, from, to);
        }
    }

    fn scan_points(&self, s: &mut Search<'_>, from: usize, to: usize) {
        for (p, &index) in self.sorted[from..to].iter().zip(&self.ids[from..to]) {
            if Some(index) != s.exclude {
                s.offer(Neighbour {
                    dist2: dist2(*p, s.q),
                    index,
                });
            }
        }
    }
}

impl KnnIndex for GridIndex<'_> {
    fn knn(&self, q: DVec3, k: usize, exclude: Option<u32>, out: &mut Vec<Neighbour>) {
        out.clear();
        if k == 0 || self.sorted.is_empty() {
            return;
        }
        let mut s = Search {
            q,
            k,
            exclude,
            tie: self.tie,
            out,
        };
        let c = self.query_cell(q);
        let budget = self.sorted.len().max(4096);
        let (mut inner, mut r) = (-1, self.cells_to_grid(c).max(1));
        let mut lookups = 0usize;
        loop {
            lookups = lookups.saturating_add(self.rows_in_block(c, r));
            if lookups > budget {
                s.out.clear();
                self.scan_points(&mut s, 0, self.sorted.len());
                return;
            }
            self.scan_shell(&mut s, c, inner, r);
            if self.block_covers_grid(c, r) {
                return;
            }
            if let Some(kth) = s.kth_dist2() {
                if self.settled(q, c, r, kth) {
                    return;
                }
            }
            (inner, r) = (r, r + 1);
        }
    }

    fn len(&self) -> usize {
        self.sorted.len()
    }
}

/// The state of one query: the best `k` so far, sorted, kept in `out`.
struct Search<'o> {
    q: DVec3,
    k: usize,
    exclude: Option<u32>,
    tie: &'o [u64],
    out: &'o mut Vec<Neighbour>,
}

impl Search<'_> {
    #[inline]
    fn offer(&mut self, cand: Neighbour) {
        let out = &mut *self.out;
        if out.len() == self.k {
            match out.last() {
                Some(last) if cand.dist2 > last.dist2 => return,
                Some(last) if neighbour_order(self.tie, &cand, last).is_ge() => return,
                _ => {}
            }
            out.pop();
        }
        let at = out.partition_point(|n| neighbour_order(self.tie, n, &cand).is_lt());
        out.insert(at, cand);
    }

    fn kth_dist2(&self) -> Option<f64> {
        (self.out.len() == self.k)
            .then(|| self.out.last().map(|n| n.dist2))
            .flatten()
    }
}

fn row_key(y: i64, z: i64, dims: [i64; 3]) -> u64 {
    (y + dims[1] * z) as u64
}

fn bounding_box(points: &[DVec3]) -> Aabb {
    points
        .par_iter()
        .fold(
            || Aabb::EMPTY,
            |mut b, p| {
                b.add(*p);
                b
            },
        )
        .reduce(|| Aabb::EMPTY, |a, b| a.union(&b))
}

/// `sqrt(T A / n)` for a surface of area `A = xy + yz + zx`; along a line
/// (zero area) `T L / n`; 1 for a single location.
fn surface_cell_guess(e: DVec3, n: usize) -> f64 {
    let n = n.max(1) as f64;
    let area = e.x * e.y + e.y * e.z + e.z * e.x;
    let guess = if area > 0.0 {
        (TARGET_PER_CELL * area / n).sqrt()
    } else {
        TARGET_PER_CELL * e.max_element() / n
    };
    if guess.is_finite() && guess > 0.0 {
        guess
    } else {
        1.0
    }
}

/// Open-addressing map from row key to its range of cells. Only looked up,
/// never iterated, so its layout cannot leak into results.
#[derive(Default)]
struct RowTable {
    slots: Vec<(u64, u32, u32)>,
    shift: u32,
}

const EMPTY_ROW: u64 = u64::MAX;

impl RowTable {
    fn new(rows: &[(u64, u32, u32)]) -> Self {
        let cap = (rows.len() * 2).next_power_of_two().max(2);
        let mut table = RowTable {
            slots: vec![(EMPTY_ROW, 0, 0); cap],
            shift: 64 - cap.trailing_zeros(),
        };
        for &row in rows {
            let mut i = table.home(row.0);
            while table.slots[i].0 != EMPTY_ROW {
                i = (i + 1) & (cap - 1);
            }
            table.slots[i] = row;
        }
        table
    }

    #[inline]
    fn home(&self, key: u64) -> usize {
        (key.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> self.shift) as usize
    }

    #[inline]
    fn get(&self, key: u64) -> Option<(u32, u32)> {
        let mask = self.slots.len().checked_sub(1)?;
        let mut i = self.home(key);
        loop {
            let (k, first, end) = *self.slots.get(i)?;
            if k == key {
                return Some((first, end));
            }
            if k == EMPTY_ROW {
                return None;
            }
            i = (i + 1) & mask;
        }
    }
}
