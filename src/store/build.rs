//! Building a store from any point source in streaming passes whose memory
//! does not grow with the number of points:
//! 1. read: parse the input once, validate, accumulate the bounding box,
//!    keep the exact coordinates and the attributes in input order
//!    (`super::ingest`), which the later passes read back;
//! 2. histogram: count points per coarse grid cell;
//! 3. plan: kd-split the histogram into tiles of at most the target size;
//! 4. scatter: write each point into its tile's slot range, through small
//!    per-tile buffers;
//! 5. sort: order each tile along a Morton curve, count exact duplicates,
//!    record block bounds;
//! 6. seal: checksum every column (`super::integrity`).

use super::attributes::AttributeSink;
use super::cells::CellCounts;
use super::exact::{for_each_exact, Coordinates, ExactSink, EXACT_FILE};
use super::ingest::first_pass;
use super::manifest::{GridSpec, Kept, Manifest, STORE_VERSION};
use super::tile_plan::{plan_tiles, CellCount, TilePlan};
use super::{save_manifest, sort, Column, PointStore, StoreError, TileEntry, BLOCK};
use super::{BLOCKS_FILE, INDEX_FILE, XYZ_FILE};
use crate::geom::Aabb;
use crate::io::PointReader;
use crate::memory::{plan, BudgetError, KernelCost, MemoryBudget, MemoryPlan};
use crate::progress::Progress;
use glam::DVec3;
use std::path::{Path, PathBuf};

pub use super::ingest::MAX_POINTS;

/// How to lay out a new store: tile size and the memory of the ingest passes.
#[derive(Clone, Debug)]
pub struct BuildOptions {
    /// How large tiles may be.
    pub tiles: TileTarget,
    /// Bytes of per-tile write buffers during the scatter pass, in total.
    pub scatter_buffer: usize,
    /// Most occupied histogram cells held at once (36 bytes each at the
    /// peak); a finer grid is coarsened until its histogram fits.
    pub histogram_cells: usize,
    /// What the store keeps of its input once built ([`Kept`]): all of it
    /// for a store that outlives its run, the exact coordinates for a mesh,
    /// nothing when an export reads the input again (66 of the 114 scratch
    /// bytes a point of a LAS 1.4 input's normals).
    pub keep: Kept,
}

/// How large tiles may be.
#[derive(Clone, Copy, Debug)]
pub enum TileTarget {
    /// At most this many core points per tile.
    Points(u64),
    /// As large as the memory plan for the kernel allows ([`MemoryPlan`]).
    Budget {
        /// The memory the run may use.
        budget: MemoryBudget,
        /// What the kernel that will run on the tiles declares it needs per point.
        cost: KernelCost,
    },
}

impl TileTarget {
    /// Core points per tile for a store of `count` points, or why the
    /// budget fits no plan.
    pub(crate) fn points(&self, count: u64) -> Result<u64, BudgetError> {
        match *self {
            TileTarget::Points(n) => Ok(n.max(1)),
            TileTarget::Budget { budget, cost } => {
                Ok(MemoryPlan::new(budget, count, &cost)?.tile_points)
            }
        }
    }
}

impl BuildOptions {
    /// Tiles, histogram and scatter buffers sized by `budget` for a kernel
    /// costing `cost`.
    pub fn within(budget: MemoryBudget, cost: KernelCost) -> Self {
        BuildOptions {
            tiles: TileTarget::Budget { budget, cost },
            scatter_buffer: plan::scatter_buffer(budget),
            histogram_cells: plan::histogram_cells(budget),
            keep: Kept::All,
        }
    }
}

impl Default for BuildOptions {
    fn default() -> Self {
        BuildOptions {
            tiles: TileTarget::Points(1 << 20),
            scatter_buffer: 32 << 20,
            histogram_cells: 1 << 23,
            keep: Kept::All,
        }
    }
}

/// Streams `reader` into a new store at `dir` (created; must not hold a store).
pub fn build_store(
    reader: &mut dyn PointReader,
    dir: &Path,
    opts: &BuildOptions,
    progress: &dyn Progress,
) -> Result<PointStore, StoreError> {
    std::fs::create_dir_all(dir).map_err(|e| StoreError::os(dir, e))?;
    // Held from the start, so a run that finds this store half-built knows
    // its builder lives (`io::reclaim`).
    let lock = super::lock::StoreLock::exclusive(dir)?;
    let source = reader.info().path.clone();
    let mut manifest = build_columns(reader, dir, opts, progress)?;
    manifest.source = source.display().to_string();
    progress.begin("checksums", 0);
    seal(dir, &mut manifest)?;
    progress.end();
    if manifest.kept == Kept::Nothing {
        drop_exact(dir, &mut manifest)?;
    }
    save_manifest(dir, &manifest)?;
    PointStore::open_fresh(dir, lock)
}

/// Checksums every column of a new store's `manifest`.
fn seal(dir: &Path, manifest: &mut Manifest) -> Result<(), StoreError> {
    let mut columns = vec![
        (XYZ_FILE.to_string(), 12),
        (INDEX_FILE.to_string(), 4),
        (BLOCKS_FILE.to_string(), 24),
        (EXACT_FILE.to_string(), manifest.coordinates.item_bytes()),
    ];
    let kept = manifest.kept == Kept::All;
    for a in manifest.attributes.iter().filter(|_| kept) {
        columns.push((super::attributes::column_file(*a), a.item_bytes()));
    }
    if let Some(las) = manifest.las.filter(|_| kept) {
        let name = super::las_kept::LAS_RECORDS_FILE.to_string();
        columns.push((name, usize::from(las.record_len)));
    }
    for (name, bytes) in columns {
        let sums = super::integrity::sums_in(dir, manifest, &name, bytes)?;
        manifest.checksums.insert(name, sums);
    }
    Ok(())
}

/// Removes the exact coordinates once the build's passes have read them,
/// keeping their checksums as the input's fingerprint (`input_sums`).
fn drop_exact(dir: &Path, manifest: &mut Manifest) -> Result<(), StoreError> {
    manifest.input_sums = manifest.checksums.remove(EXACT_FILE).unwrap_or_default();
    let path = dir.join(EXACT_FILE);
    std::fs::remove_file(&path).map_err(|e| StoreError::os(&path, e))
}

fn build_columns(
    reader: &mut dyn PointReader,
    dir: &Path,
    opts: &BuildOptions,
    progress: &dyn Progress,
) -> Result<Manifest, StoreError> {
    let listed = opts.keep != Kept::Coordinates;
    let attributes = match listed {
        true => reader.info().attributes,
        false => crate::io::AttributeSet::EMPTY,
    };
    let coordinates = Coordinates::for_input(reader.info().las_transform);
    let las = match reader.info().format {
        crate::io::Format::Las | crate::io::Format::Laz if listed => {
            Some(super::las_kept::keep_frame(dir, &reader.info().path)?)
        }
        _ => None,
    };
    // Columns only for a store that keeps them; the maxima are found anyway.
    let mut sink = match opts.keep {
        Kept::All => AttributeSink::create(dir, attributes, las.map(|l| l.record_len))?,
        _ => AttributeSink::create(dir, crate::io::AttributeSet::EMPTY, None)?,
    };
    let mut exact = ExactSink::create(dir, coordinates)?;
    let ingested = first_pass(reader, &mut exact, &mut sink, progress)?;
    let (count, bounds) = (ingested.count, ingested.bounds);
    let maxima = sink.finish()?;
    exact.finish()?;
    if count == 0 {
        let path = reader.info().path.clone();
        return Err(match reader.left_out().unselected {
            0 => StoreError::Empty { path },
            unselected => StoreError::NoneSelected { path, unselected },
        });
    }
    // Checked once the count is known, before the points are read again.
    let target = opts.tiles.points(count)?;
    let fine = grid_for(&bounds, count);
    let points = Points {
        dir,
        coordinates,
        count,
    };
    let (cells, grid) = histogram(&points, &fine, opts.histogram_cells, progress)?;
    let plan = plan_tiles(cells, grid.dims, target);
    let origin = bounds.center();
    let mut tiles = tile_entries(&plan);
    scatter(&points, dir, &grid, &plan, &tiles, origin, opts, progress)?;
    let duplicates = sort::sort_tiles(dir, &mut tiles, progress)?;
    Ok(Manifest {
        version: STORE_VERSION,
        count,
        skipped_invalid: reader.skipped(),
        left_out: reader.left_out(),
        duplicates,
        origin: origin.to_array(),
        coordinates,
        bounds_min: bounds.min.to_array(),
        bounds_max: bounds.max.to_array(),
        spacing: None,
        grid,
        tiles,
        columns: Vec::new(),
        attributes: attributes.to_vec(),
        maxima: Some(maxima),
        las,
        kept: opts.keep,
        input_sums: Vec::new(),
        source: String::new(),
        source_has_normals: reader.info().has_normals,
        sampling: None,
        provenance: Default::default(),
        checksums: Default::default(),
        stations: ingested.stations,
        crc32: None,
    })
}

/// The input's points for the passes after the first: its exact column.
struct Points<'a> {
    dir: &'a Path,
    coordinates: Coordinates,
    count: u64,
}

impl Points<'_> {
    fn for_each(
        &self,
        f: impl FnMut(u64, &[DVec3]) -> Result<(), StoreError>,
    ) -> Result<(), StoreError> {
        let chunk = crate::io::DEFAULT_CHUNK as u64;
        for_each_exact(self.dir, self.coordinates, self.count, chunk, f)
    }
}

/// Histogram grid: cubic cells, about `sqrt(n / 16)` cells along the longest
/// axis (so a surface puts ~16 points in an occupied cell), at most 1024.
fn grid_for(bounds: &Aabb, count: u64) -> GridSpec {
    let ext = bounds.extent();
    let longest = ext.max_element();
    let per_axis = ((count as f64 / 16.0).sqrt()).clamp(8.0, 1024.0);
    let cell = if longest > 0.0 {
        longest / per_axis
    } else {
        1.0
    };
    let dims = ext
        .to_array()
        .map(|e| ((e / cell).floor() as u32 + 1).min(1 << 20));
    GridSpec {
        min: bounds.min.to_array(),
        cell,
        dims,
    }
}

fn cell_of(grid: &GridSpec, p: DVec3) -> [u32; 3] {
    let mut c = [0u32; 3];
    for a in 0..3 {
        // The cast truncates, which is the floor once negatives are clamped
        // (`floor` is a libm call on baseline x86-64).
        let f = (p[a] - grid.min[a]) / grid.cell;
        c[a] = (f.max(0.0) as u32).min(grid.dims[a] - 1);
    }
    c
}

/// Points per occupied cell of `grid`, or of a coarser grid if more than
/// `cap` cells are occupied; returns the cells and the grid they are of.
fn histogram(
    points: &Points,
    grid: &GridSpec,
    cap: usize,
    progress: &dyn Progress,
) -> Result<(Vec<CellCount>, GridSpec), StoreError> {
    let mut cells = CellCounts::new(grid.dims, cap);
    progress.begin("histogram", points.count);
    points.for_each(|_, pts| {
        for p in pts {
            cells.add(cell_of(grid, *p));
        }
        progress.advance(pts.len() as u64);
        Ok(())
    })?;
    let (cells, level) = cells.into_cells();
    progress.end();
    // Cells 2^level times as wide: `cell_of` on the coarse grid gives the
    // fine cell shifted right by `level` (the power of two scales exactly).
    let coarse = GridSpec {
        min: grid.min,
        cell: grid.cell * f64::from(1u32 << level),
        dims: grid.dims.map(|d| d.div_ceil(1 << level)),
    };
    Ok((cells, coarse))
}

fn tile_entries(plan: &TilePlan) -> Vec<TileEntry> {
    let mut start = 0;
    let mut first_block = 0;
    plan.tiles
        .iter()
        .map(|t| {
            let e = TileEntry {
                start,
                count: t.count,
                lo: t.lo,
                hi: t.hi,
                points_min: [0.0; 3],
                points_max: [0.0; 3],
                first_block,
            };
            start += t.count;
            first_block += t.count.div_ceil(BLOCK);
            e
        })
        .collect()
}

/// Per-tile write cursor with small buffers for both columns.
struct TileBuffer {
    next: u64,
    xyz: Vec<u8>,
    index: Vec<u8>,
}

/// Fewest points a tile buffers before a positioned write: fewer would make
/// the writes too short to be efficient.
const MIN_BUFFERED: usize = 256;
/// Bytes a buffered point takes (12 of coordinates, 4 of index).
const BUFFERED_BYTES: usize = 16;

#[allow(clippy::too_many_arguments)]
fn scatter(
    points: &Points,
    dir: &Path,
    grid: &GridSpec,
    plan: &TilePlan,
    tiles: &[TileEntry],
    origin: DVec3,
    opts: &BuildOptions,
    progress: &dyn Progress,
) -> Result<(), StoreError> {
    let count = points.count;
    let xyz = Column::create(&dir.join(XYZ_FILE), 12, count)?;
    let index = Column::create(&dir.join(INDEX_FILE), 4, count)?;
    let nblocks: u64 = tiles.iter().map(|t| t.count.div_ceil(BLOCK)).sum();
    Column::create(&dir.join(BLOCKS_FILE), 24, nblocks)?;
    // The buffers share `scatter_buffer` bytes whatever the tile count:
    // with more tiles than fit at MIN_BUFFERED points each, the spill is
    // read once per group of tiles that fits.
    let per_pass = (opts.scatter_buffer / (MIN_BUFFERED * BUFFERED_BYTES)).max(1);
    let per_tile = (opts.scatter_buffer / tiles.len().clamp(1, per_pass) / BUFFERED_BYTES)
        .clamp(MIN_BUFFERED, 1 << 16);
    let passes = tiles.len().div_ceil(per_pass);
    progress.begin("scatter", count * passes as u64);
    for group in tiles.chunks(per_pass).enumerate() {
        let (g, group) = group;
        let first_tile = g * per_pass;
        let mut bufs: Vec<TileBuffer> = group
            .iter()
            .map(|t| TileBuffer {
                next: t.start,
                xyz: Vec::new(),
                index: Vec::new(),
            })
            .collect();
        points.for_each(|first, pts| {
            for (i, p) in pts.iter().enumerate() {
                let t = plan.tile_of(cell_of(grid, *p)) as usize;
                let Some(b) = t.checked_sub(first_tile).and_then(|k| bufs.get_mut(k)) else {
                    continue;
                };
                if b.index.capacity() == 0 {
                    b.xyz.reserve_exact(per_tile * 12);
                    b.index.reserve_exact(per_tile * 4);
                }
                let rel = *p - origin;
                for v in [rel.x as f32, rel.y as f32, rel.z as f32] {
                    b.xyz.extend_from_slice(&v.to_le_bytes());
                }
                // Below MAX_POINTS (u32), checked as the input was read.
                let id = (first + i as u64) as u32;
                b.index.extend_from_slice(&id.to_le_bytes());
                if b.index.len() >= per_tile * 4 {
                    flush(b, &xyz, &index)?;
                }
            }
            progress.advance(pts.len() as u64);
            Ok(())
        })?;
        for b in &mut bufs {
            flush(b, &xyz, &index)?;
        }
    }
    progress.end();
    Ok(())
}

fn flush(b: &mut TileBuffer, xyz: &Column, index: &Column) -> Result<(), StoreError> {
    let n = (b.index.len() / 4) as u64;
    if n == 0 {
        return Ok(());
    }
    xyz.write_bytes(b.next, &b.xyz)?;
    index.write_bytes(b.next, &b.index)?;
    b.next += n;
    b.xyz.clear();
    b.index.clear();
    Ok(())
}

/// Where a store for `input` goes when the user did not build one: a scratch
/// directory beside the output, removed after the run.
pub fn scratch_store_dir(output: &Path) -> PathBuf {
    scratch_store_dir_in(&crate::io::place::directory_of(output), output)
}

/// A scratch store directory for the run writing `output`, inside `dir`.
pub fn scratch_store_dir_in(dir: &Path, output: &Path) -> PathBuf {
    let name = output
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    dir.join(format!(".{}.store-{}", name, std::process::id()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::memory::MemoryReader;
    use crate::progress::NoProgress;

    fn build(pts: &[DVec3], dir: &Path, scatter_buffer: usize) -> PointStore {
        let mut reader = MemoryReader::new("cloud", pts.to_vec(), None);
        let opts = BuildOptions {
            tiles: TileTarget::Points(300),
            scatter_buffer,
            ..BuildOptions::default()
        };
        build_store(&mut reader, dir, &opts, &NoProgress).unwrap()
    }

    #[test]
    fn scatter_in_passes_gives_the_same_store() {
        let mut rng = crate::rng::Rng::new(17);
        let pts: Vec<DVec3> = (0..20_000)
            .map(|_| DVec3::new(0.0, 0.0, 0.0).map(|_| rng.below(1 << 20) as f64 / 1e4))
            .collect();
        let dir = tempfile::tempdir().unwrap();
        let one = build(&pts, &dir.path().join("one"), 32 << 20);
        // Room for three tiles' buffers: a pass per three tiles.
        let many = build(
            &pts,
            &dir.path().join("many"),
            3 * MIN_BUFFERED * BUFFERED_BYTES,
        );
        assert!(one.tiles().len() > 30, "{} tiles", one.tiles().len());
        assert_eq!(one.manifest.tiles, many.manifest.tiles);
        for file in [XYZ_FILE, INDEX_FILE, BLOCKS_FILE] {
            let a = std::fs::read(one.dir.join(file)).unwrap();
            let b = std::fs::read(many.dir.join(file)).unwrap();
            assert!(a == b, "{file} differs");
        }
    }

    #[test]
    fn a_budget_no_plan_fits_is_refused_with_the_minimum() {
        let pts: Vec<DVec3> = (0..5000).map(|i| DVec3::new(i as f64, 0.5, 0.0)).collect();
        let mut reader = MemoryReader::new("cloud", pts, None);
        let cost = crate::normals::NormalParams::default().cost();
        let opts = BuildOptions::within(MemoryBudget::new(1024, 2), cost);
        let dir = tempfile::tempdir().unwrap();
        let err = build_store(&mut reader, &dir.path().join("s"), &opts, &NoProgress).unwrap_err();
        let needed = MemoryPlan::minimum_budget(2, 5000, &cost);
        match err {
            StoreError::Budget(BudgetError::TooSmall { needed: n, .. }) => assert_eq!(n, needed),
            e => panic!("unexpected {e}"),
        }
    }
}
