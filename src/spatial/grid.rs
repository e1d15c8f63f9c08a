//! Exact kNN over a uniform grid of cubes (paper 1 section 2.1).
//!
//! Storage is compact: the points are sorted by cell (z, then y, then x, then
//! index) into one array; each occupied cell keeps its x and its start offset;
//! each occupied row of cells (fixed y, z) is found through the row table
//! (`grid/rows.rs`), so a run of cells along x is one contiguous range.
//!
//! Deviations from the paper, with reasons:
//! - The paper searches the fixed 27 cubes around the query, which is not exact
//!   (PITFALLS.md "Neighbourhoods"). We start with those 27 and widen ring by
//!   ring until the k-th distance is inside the searched block.
//! - The paper addresses cubes by a hash of (ix, iy, iz); we look up rows (a
//!   dense array, or a hash for sparse clouds), so one lookup serves a whole
//!   run of cells along x.
//! - Rows and cells whose lower-bound distance exceeds the current k-th
//!   candidate are skipped; this drops only points that cannot qualify.
//! - The cell size is chosen from the data (see [`GridIndex::new`]) rather than
//!   from the marching-cube edge, which this stage does not know.
//! - If the search would probe more rows than there are points (at least
//!   4096; a query far outside the data, or cells far too small), it scans all
//!   points instead: same answer, cost bounded by O(n) per query.

use glam::DVec3;
use rayon::prelude::*;

use super::brute::dist2;
use super::{check_input, IndexError, KnnIndex, Neighbour};
use crate::geom::Aabb;

mod rows;
mod search;

use rows::RowTable;
use search::Search;

/// Wanted mean number of points per occupied cell. Five points per cell on
/// a surface puts the 12th neighbour inside the first 27 cells for most
/// queries while keeping the points scanned few: on a 1M-point sphere, k = 12,
/// 2.5 / 4 / 5.5 / 8 points per cell cost 8.4k / 5.7k / 5.5k / 5.7k
/// instructions per query (callgrind).
const TARGET_PER_CELL: f64 = 5.0;
/// Cells per axis are capped so that row keys fit easily in a u64.
const MAX_CELLS_PER_AXIS: f64 = (1u64 << 21) as f64;
/// Query cells are clamped to this range before the cast to i64.
const FAR_CELL: f64 = (1u64 << 40) as f64;

/// Uniform-grid exact kNN index over borrowed points.
pub struct GridIndex<'a> {
    points: &'a [DVec3],
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
    /// puts about `T` = 5 points in a cell the surface crosses. The mean
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
            if mean == 0.0 || (TARGET_PER_CELL / 4.0..=TARGET_PER_CELL * 4.0).contains(&mean) {
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

    /// The original indices of the points in cell order. Running all-points
    /// queries in this order keeps consecutive queries in nearby memory
    /// (fewer cache misses than a scattered input order).
    pub fn cell_order(&self) -> &[u32] {
        &self.ids
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
            .map(|e| (floor_to_cell(e * inv_cell) + 1).clamp(1, MAX_CELLS_PER_AXIS as i64));
        let cell_of = |p: &DVec3| {
            let t = ((*p - origin) * inv_cell).to_array();
            let c: [i64; 3] = std::array::from_fn(|a| floor_to_cell(t[a]).clamp(0, dims[a] - 1));
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
            points,
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
        let key_space = (self.dims[1] as u64).saturating_mul(self.dims[2] as u64);
        self.rows = RowTable::new(&rows, key_space, keys.len());
    }

    /// The cell containing `q`, unclamped (queries may lie outside the grid).
    fn query_cell(&self, q: DVec3) -> [i64; 3] {
        ((q - self.origin) * self.inv_cell)
            .to_array()
            .map(floor_to_cell)
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
    /// shrunk by the rounding allowance `tol`.
    fn settled(&self, s: &Search<'_>, c: [i64; 3], r: i64) -> bool {
        let (qa, oa) = (s.q.to_array(), self.origin.to_array());
        let mut margin = f64::INFINITY;
        for a in 0..3 {
            if c[a] - r > 0 {
                margin = margin.min(qa[a] - (oa[a] + (c[a] - r) as f64 * self.cell));
            }
            if c[a] + r < self.dims[a] - 1 {
                margin = margin.min(oa[a] + (c[a] + r + 1) as f64 * self.cell - qa[a]);
            }
        }
        s.bound.sqrt() * (1.0 + 8.0 * f64::EPSILON) + s.tol < margin
    }

    /// Rounding allowance (a distance) for comparing cell geometry with
    /// point distances: a few ulps of the largest coordinate involved.
    fn tolerance(&self, q: DVec3) -> f64 {
        16.0 * f64::EPSILON * (self.coord_scale + (q - self.origin).abs().max_element())
    }

    /// Distance along axis `a` from `v` to cell interval `i`, less `tol`.
    fn gap(&self, a: usize, v: f64, i: i64, tol: f64) -> f64 {
        let lo = self.origin[a] + i as f64 * self.cell;
        ((lo - v).max(v - (lo + self.cell)) - tol).max(0.0)
    }

    /// Cell index along x of coordinate `v`, unclamped.
    fn x_cell(&self, v: f64) -> i64 {
        floor_to_cell((v - self.origin.x) * self.inv_cell)
    }

    /// Scans the cells at Chebyshev distance in `(inner, r]` from cell `c`
    /// (`inner = -1` scans the whole block), skipping rows and cells whose
    /// lower-bound distance exceeds the current k-th candidate (paper 1 scans
    /// whole cubes; pruning only skips points that cannot qualify).
    fn scan_shell(&self, s: &mut Search<'_>, c: [i64; 3], inner: i64, r: i64) {
        let span = |a: usize| ((c[a] - r).max(0), (c[a] + r).min(self.dims[a] - 1));
        let ((y0, y1), (z0, z1), (x0, x1)) = (span(1), span(2), span(0));
        let centre_first = inner < 0 && (y0..=y1).contains(&c[1]) && (z0..=z1).contains(&c[2]);
        if centre_first {
            if let Some(row) = self.rows.get(row_key(c[1], c[2], self.dims)) {
                self.scan_cells(s, row, x0, x1);
            }
        }
        for z in z0..=z1 {
            let gz = self.gap(2, s.q.z, z, s.tol);
            for y in y0..=y1 {
                if centre_first && (y, z) == (c[1], c[2]) {
                    continue;
                }
                let gy = self.gap(1, s.q.y, y, s.tol);
                let Some((xa, xb)) = self.row_cells(s, gy * gy + gz * gz, (x0, x1)) else {
                    continue;
                };
                if xa > xb {
                    continue;
                }
                let Some(row) = self.rows.get(row_key(y, z, self.dims)) else {
                    continue;
                };
                if (y - c[1]).abs() <= inner && (z - c[2]).abs() <= inner {
                    self.scan_cells(s, row, xa, xb.min(c[0] - inner - 1));
                    self.scan_cells(s, row, xa.max(c[0] + inner + 1), xb);
                } else {
                    self.scan_cells(s, row, xa, xb);
                }
            }
        }
    }

    /// Scans the 27 cells around cell `c` (inside the grid), nearest rows
    /// first. Which points qualify does not depend on the order, but how
    /// soon the k-th candidate tightens does: inserting candidates in order
    /// was most of a query's instructions, and a tighter bound both rejects
    /// more of them outright and skips more rows.
    fn scan_first_block(&self, s: &mut Search<'_>, c: [i64; 3]) {
        let mut rows = [(0.0f64, 0i64, 0i64); 9];
        let mut n = 0;
        for z in (c[2] - 1).max(0)..=(c[2] + 1).min(self.dims[2] - 1) {
            let gz = self.gap(2, s.q.z, z, s.tol);
            for y in (c[1] - 1).max(0)..=(c[1] + 1).min(self.dims[1] - 1) {
                let gy = self.gap(1, s.q.y, y, s.tol);
                rows[n] = (gy * gy + gz * gz, y, z);
                n += 1;
            }
        }
        let rows = &mut rows[..n];
        rows.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
        let (x0, x1) = ((c[0] - 1).max(0), (c[0] + 1).min(self.dims[0] - 1));
        for &(g2, y, z) in rows.iter() {
            // Rows come by increasing gap: once one is out, the rest are.
            let Some((xa, xb)) = self.row_cells(s, g2, (x0, x1)) else {
                break;
            };
            if let Some(row) = self.rows.get(row_key(y, z, self.dims)) {
                self.scan_cells(s, row, xa, xb);
            }
        }
    }

    /// The cells of `xs` in a row at squared gap `g2` (y and z) from the
    /// query that can still hold a candidate, or `None` when the whole row
    /// lies beyond the k-th candidate.
    fn row_cells(&self, s: &Search<'_>, g2: f64, (x0, x1): (i64, i64)) -> Option<(i64, i64)> {
        if !s.bound.is_finite() {
            return Some((x0, x1));
        }
        let rest = s.pruning_bound() - g2;
        if rest < 0.0 {
            return None;
        }
        let reach = rest.sqrt() + s.tol;
        Some((
            x0.max(self.x_cell(s.q.x - reach)),
            x1.min(self.x_cell(s.q.x + reach)),
        ))
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
        // Rows crossed by a surface are short: scan them; bisect long ones.
        let (lo, hi) = (x0.max(0) as u32, x1.min(u32::MAX as i64) as u32);
        let first = if cells.len() <= 16 {
            cells.iter().take_while(|&&x| x < lo).count()
        } else {
            cells.partition_point(|&x| x < lo)
        };
        let taken = cells[first..].iter().take_while(|&&x| x <= hi).count();
        let (a, b) = (row.0 as usize + first, row.0 as usize + first + taken);
        if a < b {
            let (from, to) = (self.cell_start[a] as usize, self.cell_start[b] as usize);
            self.scan_points(s, from, to);
        }
    }

    fn scan_points(&self, s: &mut Search<'_>, from: usize, to: usize) {
        s.offer_all(&self.sorted[from..to], &self.ids[from..to]);
    }
}

impl GridIndex<'_> {
    /// The nearest point to `q` into `out`, exactly as `knn(q, 1, None,
    /// out)` gives it, with the search started from `hint`: the original
    /// index and position of a point that may lie near `q` (the previous
    /// query's answer, say). A close hint bounds the search from its first
    /// cell, so fewer points are scanned and inserted; any valid hint gives
    /// the same answer, because every point is still offered.
    pub fn nearest_from(&self, q: DVec3, hint: (u32, DVec3), out: &mut Vec<Neighbour>) {
        out.clear();
        if self.sorted.is_empty() {
            return;
        }
        let mut s = Search::new(q, 1, None, self.tie, self.tolerance(q), out);
        if (hint.0 as usize) < self.tie.len() {
            s.offer_all(&[hint.1], &[hint.0]);
        }
        self.run(&mut s, q);
    }

    /// Widens the search block around `q` until `s` is settled.
    fn run(&self, s: &mut Search<'_>, q: DVec3) {
        let c = self.query_cell(q);
        let budget = self.sorted.len().max(4096);
        let (mut inner, mut r) = (-1, self.cells_to_grid(c).max(1));
        let mut lookups = 0usize;
        loop {
            lookups = lookups.saturating_add(self.rows_in_block(c, r));
            if lookups > budget {
                s.restart();
                self.scan_points(s, 0, self.sorted.len());
                break;
            }
            if inner < 0 && r == 1 {
                self.scan_first_block(s, c);
            } else {
                self.scan_shell(s, c, inner, r);
            }
            if self.block_covers_grid(c, r) || (s.is_full() && self.settled(s, c, r)) {
                break;
            }
            (inner, r) = (r, r + 1);
        }
    }
}

impl GridIndex<'_> {
    /// The `k` nearest points to `q` into `out`, exactly as `knn(q, k,
    /// None, out)` gives them, with the search bounded from the start by
    /// the points `out` holds on entry (an earlier answer over this index,
    /// for a query nearby): `k` of them lie within the farthest one's
    /// distance, so no point beyond it can be among the nearest, and the
    /// scan inserts and visits fewer. Any entry gives the same answer.
    pub fn knn_near(&self, q: DVec3, k: usize, out: &mut Vec<Neighbour>) {
        let bound = match out.get(..k) {
            Some(hints) if k > 0 => {
                hints
                    .iter()
                    .fold(0.0f64, |m, h| match self.points.get(h.index as usize) {
                        Some(&p) => m.max(dist2(p, q)),
                        None => f64::INFINITY,
                    })
            }
            _ => f64::INFINITY,
        };
        out.clear();
        if k == 0 || self.sorted.is_empty() {
            return;
        }
        let mut s = Search::new(q, k, None, self.tie, self.tolerance(q), out);
        s.bound = bound;
        self.run(&mut s, q);
    }
}

impl KnnIndex for GridIndex<'_> {
    fn knn(&self, q: DVec3, k: usize, exclude: Option<u32>, out: &mut Vec<Neighbour>) {
        out.clear();
        if k == 0 || self.sorted.is_empty() {
            return;
        }
        let mut s = Search::new(q, k, exclude, self.tie, self.tolerance(q), out);
        self.run(&mut s, q);
    }

    fn len(&self) -> usize {
        self.sorted.len()
    }
}

/// `floor(t)` clamped to the far-cell range, as an integer (NaN gives 0).
/// Written out because `f64::floor` is a library call on baseline x86-64.
#[inline]
fn floor_to_cell(t: f64) -> i64 {
    let t = t.clamp(-FAR_CELL, FAR_CELL);
    let i = t as i64;
    if (i as f64) > t {
        i - 1
    } else {
        i
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
