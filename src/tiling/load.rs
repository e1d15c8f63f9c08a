//! Loading one tile: its core points (a contiguous store range) followed by
//! the margin, every point of other tiles inside the core box grown by the
//! margin. Only the blocks whose bounds meet that region are read.

use crate::geom::Aabb;
use crate::store::{Column, ColumnSpec, Item, PointStore, StoreError, TileEntry, BLOCK};
use crate::store::{FLAGS, NORMALS};
use glam::DVec3;

/// A tile's points in memory, core first, coordinates relative to the store
/// origin (f64 converted from the stored f32, so every tile sees bit-identical
/// values for a point).
#[derive(Clone, Debug)]
pub struct TilePoints {
    /// 0-based index of the tile in the store.
    pub tile: usize,
    /// Core points, then margin points, relative to the store origin.
    pub points: Vec<DVec3>,
    /// Input-order index of each point: the global tie-break key.
    pub ids: Vec<u64>,
    /// Store index of the first core point; core point `i` is `store_first + i`.
    pub store_first: u64,
    /// Store index of each margin point (point `n_core + m` is
    /// `margin_store[m]`): global passes key per-point state by store index,
    /// which follows space where input ids do not.
    pub margin_store: Vec<u64>,
    /// How many of `points` are the core (the tile's own results).
    pub n_core: usize,
    /// Core box; faces on the outside of the store grid lie at infinity, so
    /// the cores partition all of space.
    pub core: Aabb,
    /// The region whose points are all loaded: `core` grown by `margin`.
    pub loaded: Aabb,
    /// How far the loaded region reaches beyond the core.
    pub margin: f64,
    /// The store columns the kernel declared it reads, for every loaded
    /// point (a kernel declares them: `TileKernel::reads`).
    pub columns: Vec<TileColumn>,
}

/// A kernel read normals from a tile loaded without them (it did not
/// declare them in `reads`): a programming error, reported rather than
/// read as "no normal here".
#[derive(Debug, thiserror::Error)]
#[error("the tile was loaded without the normals and flags columns")]
pub struct MissingColumns;

/// One store column's values for a tile's loaded points.
#[derive(Clone, Debug, PartialEq)]
pub struct TileColumn {
    /// Which column.
    pub spec: ColumnSpec,
    /// Its values, one item per loaded point.
    pub values: Values,
}

/// Loaded values, typed by the column's item.
#[derive(Clone, Debug, PartialEq)]
pub enum Values {
    /// One vector per point (normals).
    Vec3(Vec<DVec3>),
    /// `n` values per point, flat.
    F32(Vec<f32>),
    /// One byte per point (flags).
    U8(Vec<u8>),
}

impl Values {
    fn empty(item: Item) -> Self {
        match item {
            Item::Vec3 => Values::Vec3(Vec::new()),
            Item::F32(_) => Values::F32(Vec::new()),
            Item::U8 => Values::U8(Vec::new()),
        }
    }

    /// Appends point `k` of a range read into `raw` (f32 or byte items).
    fn push(&mut self, item: Item, raw: &Raw, k: usize) {
        match (self, raw) {
            (Values::Vec3(v), Raw::F32(f)) => {
                let n = &f[3 * k..3 * k + 3];
                v.push(DVec3::new(n[0] as f64, n[1] as f64, n[2] as f64));
            }
            (Values::F32(v), Raw::F32(f)) => {
                let w = item.bytes() / 4;
                v.extend_from_slice(&f[w * k..w * (k + 1)]);
            }
            (Values::U8(v), Raw::U8(b)) => v.push(b[k]),
            // `Raw::for_item` reads every item type as its own kind.
            _ => {}
        }
    }
}

impl TilePoints {
    /// Distance from `p` to the edge of the loaded region: every point within
    /// this distance of `p` is loaded.
    pub fn room(&self, p: DVec3) -> f64 {
        let lo = p - self.loaded.min;
        let hi = self.loaded.max - p;
        lo.min(hi).min_element()
    }

    /// How far a dependence of `p` reaching `reach` extends beyond the
    /// loaded region (0 when it lies inside; infinite when it is unbounded).
    pub fn shortfall(&self, p: DVec3, reach: f64) -> f64 {
        let room = self.room(p);
        if reach <= room {
            0.0
        } else {
            reach - room
        }
    }

    /// Store index of loaded point `i`.
    pub fn store_index(&self, i: usize) -> u64 {
        match i.checked_sub(self.n_core) {
            None => self.store_first + i as u64,
            Some(m) => self.margin_store[m],
        }
    }

    /// The core points: those whose results this tile gives.
    pub fn core_points(&self) -> &[DVec3] {
        &self.points[..self.n_core]
    }

    /// A tile holding all of `points` as its core (ids 0..n), with space
    /// unbounded: what an untiled run of a kernel sees.
    pub fn whole(points: Vec<DVec3>) -> Self {
        let everywhere = Aabb::new(DVec3::NEG_INFINITY, DVec3::INFINITY);
        TilePoints {
            tile: 0,
            ids: (0..points.len() as u64).collect(),
            n_core: points.len(),
            points,
            store_first: 0,
            margin_store: Vec::new(),
            core: everywhere,
            loaded: everywhere,
            margin: f64::INFINITY,
            columns: Vec::new(),
        }
    }

    /// The loaded values of column `spec`, if the kernel declared it.
    pub fn column(&self, spec: &ColumnSpec) -> Option<&Values> {
        self.columns
            .iter()
            .find(|c| c.spec == *spec)
            .map(|c| &c.values)
    }

    /// Oriented unit normals of every loaded point; `None` unless the
    /// kernel reads [`NORMALS`] (never an empty stand-in that a caller
    /// could mistake for "no normal here").
    pub fn normals(&self) -> Option<&[DVec3]> {
        match self.column(&NORMALS) {
            Some(Values::Vec3(v)) => Some(v),
            _ => None,
        }
    }

    /// The normals pass's flags of every loaded point; `None` unless the
    /// kernel reads [`FLAGS`].
    pub fn flags(&self) -> Option<&[u8]> {
        match self.column(&FLAGS) {
            Some(Values::U8(v)) => Some(v),
            _ => None,
        }
    }

    /// The normals and flags of every loaded point, or the error a kernel
    /// that declared them returns when they are missing.
    pub fn oriented(&self) -> Result<(&[DVec3], &[u8]), MissingColumns> {
        match (self.normals(), self.flags()) {
            (Some(n), Some(f)) => Ok((n, f)),
            _ => Err(MissingColumns),
        }
    }

    /// Attaches `values` as column `spec` (tests and untiled callers that
    /// build a tile by hand).
    pub fn with_column(mut self, spec: ColumnSpec, values: Values) -> Self {
        self.columns.retain(|c| c.spec != spec);
        self.columns.push(TileColumn { spec, values });
        self
    }
}

/// Core box of `tile` relative to the store origin, outer faces at infinity.
pub fn core_box(store: &PointStore, tile: &TileEntry) -> Aabb {
    let g = &store.manifest().grid;
    let origin = store.origin();
    let mut min = DVec3::ZERO;
    let mut max = DVec3::ZERO;
    for a in 0..3 {
        min[a] = if tile.lo[a] == 0 {
            f64::NEG_INFINITY
        } else {
            g.min[a] + tile.lo[a] as f64 * g.cell - origin[a]
        };
        max[a] = if tile.hi[a] >= g.dims[a] {
            f64::INFINITY
        } else {
            g.min[a] + tile.hi[a] as f64 * g.cell - origin[a]
        };
    }
    Aabb::new(min, max)
}

/// Faces of the loaded region beyond all stored points move to infinity: no
/// point lies there, so the region is complete in that direction.
fn unbounded_beyond(mut region: Aabb, data: &Aabb) -> Aabb {
    for a in 0..3 {
        if region.min[a] < data.min[a] {
            region.min[a] = f64::NEG_INFINITY;
        }
        if region.max[a] > data.max[a] {
            region.max[a] = f64::INFINITY;
        }
    }
    region
}

pub(crate) fn entry_bounds(t: &TileEntry) -> Aabb {
    Aabb::new(
        DVec3::from_array(t.points_min.map(f64::from)),
        DVec3::from_array(t.points_max.map(f64::from)),
    )
}

/// Loads tile `tile` with all points within `margin` (per axis) of its core,
/// and their values of the columns `reads`.
pub fn load_tile(
    store: &PointStore,
    tile: usize,
    margin: f64,
    reads: &[ColumnSpec],
) -> Result<TilePoints, StoreError> {
    let entry = &store.tiles()[tile];
    let core = core_box(store, entry);
    let loaded = unbounded_beyond(core.expanded(margin), &store.relative_bounds());
    let mut tp = TilePoints {
        tile,
        points: Vec::new(),
        ids: Vec::new(),
        store_first: entry.start,
        margin_store: Vec::new(),
        n_core: entry.count as usize,
        core,
        loaded,
        margin,
        columns: reads
            .iter()
            .map(|spec| TileColumn {
                spec: *spec,
                values: Values::empty(spec.item),
            })
            .collect(),
    };
    let files = reads
        .iter()
        .map(|spec| store.column(spec))
        .collect::<Result<Vec<Column>, _>>()?;
    let mut scratch = Scratch {
        raw: reads.iter().map(|s| Raw::for_item(s.item)).collect(),
        ..Scratch::default()
    };
    append_range(
        store,
        entry.start,
        entry.count,
        None,
        &files,
        &mut tp,
        &mut scratch,
    )?;
    for (i, other) in store.tiles().iter().enumerate() {
        if i != tile && other.count > 0 && entry_bounds(other).intersects(&loaded) {
            gather_margin(store, other, &loaded, &files, &mut tp, &mut scratch)?;
        }
    }
    Ok(tp)
}

/// Points read at once while counting.
const COUNT_CHUNK: u64 = 16 * BLOCK;

/// How many points `load_tile(store, tile, margin, _)` would load, counted
/// without holding them (the positions of the meeting blocks are read and
/// dropped a few blocks at a time): a kernel asks for its memory before the
/// load, so a tile whose margin grew past the budget is refused, or waits,
/// without first holding its points.
pub fn count_loaded(store: &PointStore, tile: usize, margin: f64) -> Result<u64, StoreError> {
    let entry = &store.tiles()[tile];
    let loaded = unbounded_beyond(
        core_box(store, entry).expanded(margin),
        &store.relative_bounds(),
    );
    let (mut blocks, mut pts) = (Vec::new(), Vec::new());
    let mut n = entry.count;
    for (i, other) in store.tiles().iter().enumerate() {
        if i == tile || other.count == 0 || !entry_bounds(other).intersects(&loaded) {
            continue;
        }
        for (first, count) in meeting_runs(store, other, &loaded, &mut blocks)? {
            // A few blocks at a time: counting must not hold a tile's points.
            for at in (first..first + count).step_by(COUNT_CHUNK as usize) {
                store.read_points(at, COUNT_CHUNK.min(first + count - at), &mut pts)?;
                n += pts.iter().filter(|p| loaded.contains(**p)).count() as u64;
            }
        }
    }
    Ok(n)
}

/// A column range as read from disk.
enum Raw {
    F32(Vec<f32>),
    U8(Vec<u8>),
}

impl Raw {
    fn for_item(item: Item) -> Self {
        match item {
            Item::Vec3 | Item::F32(_) => Raw::F32(Vec::new()),
            Item::U8 => Raw::U8(Vec::new()),
        }
    }

    fn read(&mut self, column: &Column, first: u64, count: u64) -> Result<(), StoreError> {
        match self {
            Raw::F32(v) => column.read_f32(first, count, v),
            Raw::U8(v) => column.read_u8(first, count, v),
        }
    }
}

#[derive(Default)]
struct Scratch {
    blocks: Vec<Aabb>,
    pts: Vec<DVec3>,
    ids: Vec<u64>,
    raw: Vec<Raw>,
}

/// Appends points `[first, first+count)` with their ids and the values of
/// the loaded columns (`files`, in `tp.columns` order): all of them (the
/// core, `region` is `None`), or the margin points inside `region`, whose
/// store indices are kept too.
fn append_range(
    store: &PointStore,
    first: u64,
    count: u64,
    region: Option<&Aabb>,
    files: &[Column],
    tp: &mut TilePoints,
    s: &mut Scratch,
) -> Result<(), StoreError> {
    store.read_points(first, count, &mut s.pts)?;
    store.read_indices(first, count, &mut s.ids)?;
    for (raw, file) in s.raw.iter_mut().zip(files) {
        raw.read(file, first, count)?;
    }
    for (k, p) in s.pts.iter().enumerate() {
        if region.is_some_and(|r| !r.contains(*p)) {
            continue;
        }
        if region.is_some() {
            tp.margin_store.push(first + k as u64);
        }
        tp.points.push(*p);
        tp.ids.push(s.ids[k]);
        for (col, raw) in tp.columns.iter_mut().zip(&s.raw) {
            col.values.push(col.spec.item, raw, k);
        }
    }
    Ok(())
}

fn gather_margin(
    store: &PointStore,
    other: &TileEntry,
    loaded: &Aabb,
    files: &[Column],
    tp: &mut TilePoints,
    s: &mut Scratch,
) -> Result<(), StoreError> {
    for (first, count) in meeting_runs(store, other, loaded, &mut s.blocks)? {
        append_range(store, first, count, Some(loaded), files, tp, s)?;
    }
    Ok(())
}

/// The store ranges of `other` whose blocks meet `loaded`, each run of
/// meeting blocks coalesced into one range to read.
fn meeting_runs(
    store: &PointStore,
    other: &TileEntry,
    loaded: &Aabb,
    blocks: &mut Vec<Aabb>,
) -> Result<Vec<(u64, u64)>, StoreError> {
    let nblocks = other.count.div_ceil(BLOCK);
    store.read_blocks(other.first_block, nblocks, blocks)?;
    let mut runs = Vec::new();
    let mut b = 0;
    while b < nblocks as usize {
        if !blocks[b].intersects(loaded) {
            b += 1;
            continue;
        }
        let run_start = b;
        while b < nblocks as usize && blocks[b].intersects(loaded) {
            b += 1;
        }
        let first = other.start + run_start as u64 * BLOCK;
        let end = (other.start + b as u64 * BLOCK).min(other.start + other.count);
        runs.push((first, end - first));
    }
    Ok(runs)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    #[test]
    fn the_count_before_a_load_is_the_load() {
        let mut rng = Rng::new(3);
        // Dense in one corner, sparse elsewhere: margins meet blocks in part.
        let pts: Vec<DVec3> = (0..12_000)
            .map(|i| {
                let s = if i % 3 == 0 { 10.0 } else { 2.0 };
                let (x, y) = (rng.range(0.0, s), rng.range(0.0, s));
                DVec3::new(x, y, (x * 0.7).sin())
            })
            .collect();
        let dir = tempfile::tempdir().unwrap();
        let store = crate::store::test_store::store_of(pts, 1500, &dir.path().join("s"));
        assert!(store.tiles().len() > 4);
        for t in 0..store.tiles().len() {
            for margin in [0.0, 0.05, 0.4, 3.0, 50.0] {
                let loaded = load_tile(&store, t, margin, &[]).unwrap().points.len();
                assert_eq!(
                    count_loaded(&store, t, margin).unwrap(),
                    loaded as u64,
                    "tile {t} margin {margin}"
                );
            }
        }
    }
}
