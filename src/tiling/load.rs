//! Loading one tile: its core points (a contiguous store range) followed by
//! the margin, every point of other tiles inside the core box grown by the
//! margin. Only the blocks whose bounds meet that region are read.

use crate::geom::Aabb;
use crate::store::{Column, PointStore, StoreError, TileEntry, BLOCK, FLAGS_FILE, NORMAL_FILE};
use glam::DVec3;

/// A tile's points in memory, core first, coordinates relative to the store
/// origin (f64 converted from the stored f32, so every tile sees bit-identical
/// values for a point).
#[derive(Clone, Debug)]
pub struct TilePoints {
    pub tile: usize,
    pub points: Vec<DVec3>,
    /// Input-order index of each point: the global tie-break key.
    pub ids: Vec<u64>,
    /// Store index of the first core point; core point `i` is `store_first + i`.
    pub store_first: u64,
    /// Store index of each margin point (point `n_core + m` is
    /// `margin_store[m]`): global passes key per-point state by store index,
    /// which follows space where input ids do not.
    pub margin_store: Vec<u64>,
    pub n_core: usize,
    /// Core box; faces on the outside of the store grid lie at infinity, so
    /// the cores partition all of space.
    pub core: Aabb,
    /// The region whose points are all loaded: `core` grown by `margin`.
    pub loaded: Aabb,
    pub margin: f64,
    /// Oriented unit normals and flags of every loaded point, when the
    /// kernel asked for them (empty otherwise).
    pub normals: Vec<DVec3>,
    pub flags: Vec<u8>,
}

impl TilePoints {
    /// Distance from `p` to the edge of the loaded region: every point within
    /// this distance of `p` is loaded.
    pub fn room(&self, p: DVec3) -> f64 {
        let lo = p - self.loaded.min;
        let hi = self.loaded.max - p;
        lo.min(hi).min_element()
    }

    /// Store index of loaded point `i`.
    pub fn store_index(&self, i: usize) -> u64 {
        match i.checked_sub(self.n_core) {
            None => self.store_first + i as u64,
            Some(m) => self.margin_store[m],
        }
    }

    pub fn core_points(&self) -> &[DVec3] {
        &self.points[..self.n_core]
    }
}

/// Core box of `tile` relative to the store origin, outer faces at infinity.
pub fn core_box(store: &PointStore, tile: &TileEntry) -> Aabb {
    let g = &store.manifest.grid;
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

fn entry_bounds(t: &TileEntry) -> Aabb {
    Aabb::new(
        DVec3::from_array(t.points_min.map(f64::from)),
        DVec3::from_array(t.points_max.map(f64::from)),
    )
}

/// Loads tile `tile` with all points within `margin` (per axis) of its core,
/// and their normals and flags when `with_normals`.
pub fn load_tile(
    store: &PointStore,
    tile: usize,
    margin: f64,
    with_normals: bool,
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
        normals: Vec::new(),
        flags: Vec::new(),
    };
    let attrs = if with_normals {
        Some(Attributes {
            normals: store.attribute(NORMAL_FILE, 12)?,
            flags: store.attribute(FLAGS_FILE, 1)?,
        })
    } else {
        None
    };
    let mut scratch = Scratch::default();
    append_range(
        store,
        entry.start,
        entry.count,
        None,
        attrs.as_ref(),
        &mut tp,
        &mut scratch,
    )?;
    for (i, other) in store.tiles().iter().enumerate() {
        if i != tile && other.count > 0 && entry_bounds(other).intersects(&loaded) {
            gather_margin(store, other, &loaded, attrs.as_ref(), &mut tp, &mut scratch)?;
        }
    }
    Ok(tp)
}

struct Attributes {
    normals: Column,
    flags: Column,
}

#[derive(Default)]
struct Scratch {
    blocks: Vec<Aabb>,
    pts: Vec<DVec3>,
    ids: Vec<u64>,
    nrm: Vec<f32>,
    flg: Vec<u8>,
}

/// Appends points `[first, first+count)` with their ids and, if asked,
/// attributes: all of them (the core, `region` is `None`), or the margin
/// points inside `region`, whose store indices are kept too.
fn append_range(
    store: &PointStore,
    first: u64,
    count: u64,
    region: Option<&Aabb>,
    attrs: Option<&Attributes>,
    tp: &mut TilePoints,
    s: &mut Scratch,
) -> Result<(), StoreError> {
    store.read_points(first, count, &mut s.pts)?;
    store.read_indices(first, count, &mut s.ids)?;
    if let Some(a) = attrs {
        a.normals.read_f32(first, count, &mut s.nrm)?;
        a.flags.read_u8(first, count, &mut s.flg)?;
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
        if attrs.is_some() {
            let n = &s.nrm[3 * k..3 * k + 3];
            tp.normals
                .push(DVec3::new(n[0] as f64, n[1] as f64, n[2] as f64));
            tp.flags.push(s.flg[k]);
        }
    }
    Ok(())
}

fn gather_margin(
    store: &PointStore,
    other: &TileEntry,
    loaded: &Aabb,
    attrs: Option<&Attributes>,
    tp: &mut TilePoints,
    s: &mut Scratch,
) -> Result<(), StoreError> {
    let nblocks = other.count.div_ceil(BLOCK);
    store.read_blocks(other.first_block, nblocks, &mut s.blocks)?;
    let mut b = 0;
    while b < nblocks as usize {
        if !s.blocks[b].intersects(loaded) {
            b += 1;
            continue;
        }
        // Coalesce a run of meeting blocks into one read.
        let run_start = b;
        while b < nblocks as usize && s.blocks[b].intersects(loaded) {
            b += 1;
        }
        let first = other.start + run_start as u64 * BLOCK;
        let end = (other.start + b as u64 * BLOCK).min(other.start + other.count);
        append_range(store, first, end - first, Some(loaded), attrs, tp, s)?;
    }
    Ok(())
}
