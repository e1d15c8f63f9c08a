//! One lattice job (`lattice.rs`): the growth of paper 2 (`grow.rs`) over
//! the points of the job's view, with the lower levels' triangles there
//! fixed (their open vertices FRINGE, in input-id order, then the still
//! free points of the window as seeds, in input-id order), growing a
//! little beyond the window and keeping the triangles whose three vertices
//! lie in it.
//!
//! A pure function of the points in the view (positions, ids, planes,
//! spacings, lists, thinning) and of the lower jobs' outputs there: every
//! array is built in input-id order, lower triangles in job-key order, so
//! a tile and the whole cloud run the same job to the same bytes.
//!
//! Orientation pieces are named by the input id of the point whose growth
//! began them, so names mean the same in every tile. A job hands back its
//! triangles wound in their piece root's frame, and the relations it found
//! between the pieces it was given (and those its lower jobs recorded).

use super::cloud::{Cloud, Csr, Neighbourhoods};
use super::grow::Grower;
use super::lattice::{JobKey, Lattice, LEVELS};
use super::local::PointInfo;
use super::orient::flipped;
use super::params::ProjectionParams;
use super::probe::Probe;
use super::surface::{State, Surface, NONE};
use crate::geom::Aabb;
use crate::spatial::key_runs;
use glam::DVec3;
use rayon::prelude::*;
use std::collections::HashMap;

/// What a job made.
#[derive(Debug, Default)]
pub struct JobOutput {
    /// Triangles (tile-local indices), wound in their piece's frame.
    pub tris: Vec<[u32; 3]>,
    /// Index into `names` of each triangle's piece.
    pub piece: Vec<u32>,
    pub names: Vec<u64>,
    /// `(a, b, parity)`: pieces `a` and `b` are wound oppositely when
    /// `parity` is set.
    pub relations: Vec<(u64, u64, bool)>,
    pub processed: u64,
    /// The box of each run of [`CHUNK`] triangles (in order): a higher job
    /// skips the runs that miss its view without reading their corners.
    pub chunks: Vec<Aabb>,
}

/// Triangles per box in [`JobOutput::chunks`].
pub const CHUNK: usize = 32;

/// A tile's points as the jobs read them (tile-local indices).
pub struct TileView<'a, H: Neighbourhoods> {
    pub points: &'a [DVec3],
    pub ids: &'a [u64],
    pub info: &'a [PointInfo],
    pub hoods: &'a H,
    pub buckets: &'a Buckets,
    /// The tile's points in input-id order, and each point's place there.
    pub by_id: &'a [u32],
    pub rank: &'a [u32],
    /// [`super::cloud::Cloud::slack`]: the same for every tile.
    pub slack: f64,
}

/// `(by_id, rank)`: the points in input-id order and each one's place in
/// it, so that a job sorts its points by comparing plain integers.
pub fn id_order(ids: &[u64]) -> (Vec<u32>, Vec<u32>) {
    let mut by_id: Vec<u32> = (0..ids.len() as u32).collect();
    by_id.par_sort_unstable_by_key(|&i| ids[i as usize]);
    let mut rank = vec![0u32; ids.len()];
    for (r, &i) in by_id.iter().enumerate() {
        rank[i as usize] = r as u32;
    }
    (by_id, rank)
}

/// Tile points by coarse cell, to find a view's points without a scan.
pub struct Buckets {
    size: f64,
    order: Vec<u32>,
    ranges: HashMap<[i64; 3], (u32, u32)>,
}

impl Buckets {
    pub fn new(points: &[DVec3], size: f64) -> Self {
        let key = |p: DVec3| [p.x, p.y, p.z].map(|c| (c / size).floor() as i64);
        let mut keyed: Vec<([i64; 3], u32)> = points
            .par_iter()
            .enumerate()
            .map(|(i, p)| (key(*p), i as u32))
            .collect();
        keyed.par_sort_unstable();
        let ranges = key_runs(&keyed, |e| e.0).collect();
        Buckets {
            size,
            order: keyed.into_iter().map(|e| e.1).collect(),
            ranges,
        }
    }

    /// The points inside `b` (closed), in no particular order.
    pub fn inside(&self, points: &[DVec3], b: &Aabb, out: &mut Vec<u32>) {
        let lo = (b.min / self.size).floor();
        let hi = (b.max / self.size).floor();
        for x in lo.x as i64..=hi.x as i64 {
            for y in lo.y as i64..=hi.y as i64 {
                for z in lo.z as i64..=hi.z as i64 {
                    let Some(&(s, e)) = self.ranges.get(&[x, y, z]) else {
                        continue;
                    };
                    for &i in &self.order[s as usize..e as usize] {
                        let p = points[i as usize];
                        if p.cmpge(b.min).all() && p.cmple(b.max).all() {
                            out.push(i);
                        }
                    }
                }
            }
        }
    }
}

/// A job's points, in input-id order, then the ghosts (far corners of
/// lower triangles).
#[derive(Default)]
struct JobPoints {
    tile: Vec<u32>,
    points: Vec<DVec3>,
    ids: Vec<u64>,
    normals: Vec<DVec3>,
    spacing: Vec<f64>,
    centre: Vec<bool>,
    joinable: Vec<bool>,
    keep: Vec<bool>,
    /// Outside the window, but a kept triangle may still reach it (see
    /// `may_borrow`).
    borrow: Vec<bool>,
    unused: Vec<bool>,
}

impl JobPoints {
    fn with_capacity(n: usize) -> Self {
        JobPoints {
            tile: Vec::with_capacity(n),
            points: Vec::with_capacity(n),
            ids: Vec::with_capacity(n),
            normals: Vec::with_capacity(n),
            spacing: Vec::with_capacity(n),
            centre: Vec::with_capacity(n),
            joinable: Vec::with_capacity(n),
            keep: Vec::with_capacity(n),
            borrow: Vec::with_capacity(n),
            unused: Vec::with_capacity(n),
        }
    }

    /// A point and where it lies for the job.
    fn push(&mut self, tile: u32, p: DVec3, id: u64, info: Option<&PointInfo>, at: Place) {
        let Place {
            grows,
            keep,
            borrow,
        } = at;
        self.tile.push(tile);
        self.points.push(p);
        self.ids.push(id);
        self.normals.push(info.map_or(DVec3::ZERO, |i| i.normal));
        self.spacing.push(info.map_or(0.0, |i| i.spacing));
        self.centre.push(grows && info.is_some_and(|i| i.complete));
        // A borrowed point is joined, never grown from: its fan is a
        // lower job's.
        self.joinable.push(grows || borrow);
        self.keep.push(keep);
        self.borrow.push(borrow);
        self.unused
            .push(info.is_some_and(|i| i.thinned || i.spacing == 0.0));
    }
}

/// Where a point lies for a job: in its growth box, in its window, or
/// outside the window where its triangles may still reach (`may_borrow`).
#[derive(Clone, Copy)]
struct Place {
    grows: bool,
    keep: bool,
    borrow: bool,
}

/// Tile index -> job index: a tile-sized map (`NONE` where absent) that
/// each worker reuses, cleared after every job.
pub struct ToLocal(Vec<u32>);

impl ToLocal {
    pub fn new(tile_points: usize) -> Self {
        ToLocal(vec![NONE; tile_points])
    }

    fn get(&self, tile: u32) -> Option<u32> {
        let l = self.0[tile as usize];
        (l != NONE).then_some(l)
    }
}

/// Names of pieces, densely numbered in order of appearance.
#[derive(Default)]
struct Names {
    names: Vec<u64>,
    dense: HashMap<u64, u32>,
}

impl Names {
    fn get(&mut self, name: u64) -> u32 {
        *self.dense.entry(name).or_insert_with(|| {
            self.names.push(name);
            self.names.len() as u32 - 1
        })
    }
}

/// Runs job `key`; `lower` gives the output of a lower job already run
/// (`None`: it has no points).
pub fn run_job<'a, H: Neighbourhoods>(
    key: JobKey,
    lat: &Lattice,
    tile: &TileView<H>,
    lower: &dyn Fn(JobKey) -> Option<&'a JobOutput>,
    params: &ProjectionParams,
    local: &mut ToLocal,
) -> JobOutput {
    let view = lat.view_box(key);
    let grow = lat.grow_box(key);
    let mut members = Vec::new();
    tile.buckets.inside(tile.points, &view, &mut members);
    for m in members.iter_mut() {
        *m = tile.rank[*m as usize];
    }
    members.sort_unstable();
    for m in members.iter_mut() {
        *m = tile.by_id[*m as usize];
    }
    let mut jp = JobPoints::with_capacity(members.len() + members.len() / 8);
    for &i in &members {
        let p = tile.points[i as usize];
        let info = &tile.info[i as usize];
        let grows = p.cmpge(grow.min).all() && p.cmple(grow.max).all();
        let keep = lat.in_window(key, p);
        let borrow = !keep && may_borrow(lat, key, p);
        let at = Place {
            grows,
            keep,
            borrow,
        };
        jp.push(i, p, tile.ids[i as usize], Some(info), at);
    }
    for (l, &i) in members.iter().enumerate() {
        local.0[i as usize] = l as u32;
    }
    let result = grow_job(key, lat, tile, lower, params, local, &members, jp);
    for &i in &members {
        local.0[i as usize] = NONE;
    }
    result
}

/// The job once its view's points are numbered.
#[allow(clippy::too_many_arguments)]
fn grow_job<'a, H: Neighbourhoods>(
    key: JobKey,
    lat: &Lattice,
    tile: &TileView<H>,
    lower: &dyn Fn(JobKey) -> Option<&'a JobOutput>,
    params: &ProjectionParams,
    local: &ToLocal,
    members: &[u32],
    mut jp: JobPoints,
) -> JobOutput {
    let view = lat.view_box(key);
    let n_view = members.len();
    let hoods = remap_lists(members, tile.hoods, local);
    // The lower jobs' triangles with a corner in the view.
    let mut names = Names::default();
    let mut ghosts: HashMap<u32, u32> = HashMap::new();
    let mut given: Vec<([u32; 3], u32)> = Vec::new();
    let mut relations: Vec<(u32, u32, bool)> = Vec::new();
    for level in 0..key.level {
        for k in lat.jobs_meeting(level, &view) {
            let Some(out) = lower(k) else { continue };
            for &(a, b, parity) in &out.relations {
                relations.push((names.get(a), names.get(b), parity));
            }
            let runs = out.tris.chunks(CHUNK).zip(out.piece.chunks(CHUNK));
            for ((tris, pieces), b) in runs.zip(&out.chunks) {
                if !b.intersects(&view) {
                    continue;
                }
                for (t, &piece) in tris.iter().zip(pieces) {
                    let l = t.map(|v| local.get(v));
                    if l.iter().all(Option::is_none) {
                        continue;
                    }
                    let mut lt = [0u32; 3];
                    for c in 0..3 {
                        lt[c] = match l[c] {
                            Some(x) => x,
                            None => *ghosts.entry(t[c]).or_insert_with(|| {
                                let v = t[c] as usize;
                                // Ghosts are never processed; their tie key
                                // only has to differ from every input id.
                                let id = u64::MAX - tile.ids[v];
                                let at = Place {
                                    grows: false,
                                    keep: false,
                                    borrow: false,
                                };
                                jp.push(t[c], tile.points[v], id, None, at);
                                jp.points.len() as u32 - 1
                            }),
                        };
                    }
                    given.push((lt, names.get(out.names[piece as usize])));
                }
            }
        }
    }
    let n_all = jp.points.len();
    let mut hoods = hoods;
    for _ in n_view..n_all {
        hoods.ends.push(hoods.items.len() as u32);
    }
    let pieces = names.names.len() as u32;
    let mut s = Surface::with_pieces(n_all, pieces);
    for &(a, b, parity) in &relations {
        s.pieces.union(a, b, parity);
    }
    for &(t, piece) in &given {
        s.push(t, piece);
    }
    let fixed = s.tris.len();
    let probe = Probe::new(&jp.points, &jp.ids, &jp.spacing);
    let cloud = Cloud {
        points: &jp.points,
        normals: &jp.normals,
        spacing: &jp.spacing,
        hoods: &hoods,
        centre: &jp.centre,
        joinable: &jp.joinable,
        probe: &probe,
        slack: tile.slack,
    };
    let mut grower = Grower::new(params, n_all);
    for i in 0..n_all {
        s.state[i] = if i >= n_view {
            State::Completed
        } else if jp.unused[i] {
            State::Unused
        } else if !s.has_triangles(i as u32) {
            State::Free
        } else if s.is_closed(i as u32) {
            State::Completed
        } else {
            State::Fringe
        };
        if s.state[i] == State::Fringe && jp.centre[i] {
            grower.enqueue(i as u32);
        }
    }
    // Seeds in the window only: a piece begun in the spill would be
    // dropped with it.
    let seeds: Vec<u32> = (0..n_view as u32)
        .filter(|&i| jp.centre[i as usize] && jp.keep[i as usize])
        .collect();
    grower.grow(&cloud, &mut s, &seeds);
    // Hand back the new triangles, each in its root's frame.
    let name_of = |root: u32| -> u64 {
        if root < pieces {
            names.names[root as usize]
        } else {
            jp.ids[(root - pieces) as usize]
        }
    };
    let mut out = JobOutput {
        processed: grower.processed,
        ..JobOutput::default()
    };
    let mut out_names = Names::default();
    for tri in fixed..s.tris.len() {
        let t = s.tris[tri];
        let kept = |v: u32| jp.keep[v as usize];
        let reached = |v: u32| kept(v) || jp.borrow[v as usize];
        if !(t.iter().any(|&v| kept(v)) && t.iter().all(|&v| reached(v))) {
            continue;
        }
        let (root, flip) = s.orientation(tri as u32);
        let t = if flip { flipped(t) } else { t };
        out.tris.push(t.map(|v| jp.tile[v as usize]));
        out.piece.push(out_names.get(name_of(root)));
    }
    out.names = out_names.names;
    out.chunks = out
        .tris
        .chunks(CHUNK)
        .map(|run| {
            let mut b = Aabb::EMPTY;
            for &v in run.iter().flatten() {
                b.add(tile.points[v as usize]);
            }
            b
        })
        .collect();
    for p in 0..pieces {
        let (root, flip) = s.pieces.find(p);
        if root != p {
            out.relations
                .push((names.names[p as usize], name_of(root), flip));
        }
    }
    out
}

/// Whether a triangle kept by `key` may have a corner at `p`, outside its
/// window: where `p` lies within [`BORROW_SPILLS`] spills of the window,
/// in a lower level's window only (those jobs ran before and left it
/// fixed), in no higher level's (whose jobs will re-grow there), and
/// within that reach of no other job of this level (which could join it
/// too). Without this, a triangle longer than the overlap (8 units:
/// sparse ground, where the local spacing is 2 to 3 units) that spans
/// from within the band of a plane to beyond the overlap lies in no
/// window, so no job keeps it and a hole is left.
fn may_borrow(lat: &Lattice, key: JobKey, p: DVec3) -> bool {
    let in_level = |l: u8| lat.job_of(p, l).is_some();
    if !(0..key.level).any(in_level) || (key.level + 1..LEVELS).any(in_level) {
        return false;
    }
    let reach = BORROW_SPILLS * lat.spill;
    let reaches = |k: JobKey| {
        let w = lat.window(k);
        Aabb::new(w.min - DVec3::splat(reach), w.max + DVec3::splat(reach)).contains(p)
    };
    let near = Aabb::new(p - DVec3::splat(reach), p + DVec3::splat(reach));
    reaches(key)
        && lat
            .jobs_meeting(key.level, &near)
            .into_iter()
            .all(|k| k == key || !reaches(k))
}

/// How far beyond its window, in spills, a job may join points of lower
/// windows (see `may_borrow`).
const BORROW_SPILLS: f64 = 3.0;

/// The view points' lists in job indices; neighbours outside the view are
/// dropped (only points near the view's edge have any, and they are never
/// processed).
fn remap_lists<H: Neighbourhoods>(members: &[u32], hoods: &H, local: &ToLocal) -> Csr {
    let mut out = Csr::default();
    for &i in members {
        for &j in hoods.get(i) {
            if let Some(l) = local.get(j) {
                out.items.push(l);
            }
        }
        out.ends.push(out.items.len() as u32);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::recon::projection::reconstruct::lattice;

    /// Unit 1: band 4, overlap 8, spill 2, cell 96.
    fn lat() -> Lattice {
        lattice(1.0, 3.9)
    }

    #[test]
    fn a_face_job_borrows_corners_only_beside_its_own_window() {
        let lat = lat();
        let face = |p: DVec3| lat.job_of(p, 1).expect("in a face window");
        let f = face(DVec3::new(5.0, 48.0, 48.0));
        // In the cell window, within the face job's spill: borrowed.
        let beside = DVec3::new(13.0, 48.0, 48.0);
        assert!(lat.grow_box(f).contains(beside) && !lat.in_window(f, beside));
        assert!(may_borrow(&lat, f, beside));
        // Near an edge of the lattice, where an edge job re-grows: not.
        let near_edge = DVec3::new(13.0, 13.0, 48.0);
        let g = face(DVec3::new(5.0, 22.0, 48.0));
        assert!(lat.grow_box(g).contains(near_edge));
        assert!(!may_borrow(&lat, g, near_edge));
        // A cell job has no lower level to borrow from.
        let c = lat.job_of(DVec3::new(48.0, 48.0, 48.0), 0).unwrap();
        assert!(!may_borrow(&lat, c, DVec3::new(3.0, 48.0, 48.0)));
    }

    #[test]
    fn no_point_is_borrowed_by_two_jobs_of_a_level() {
        let lat = lat();
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64 * 200.0 - 100.0
        };
        for _ in 0..20_000 {
            let p = DVec3::new(next(), next(), next());
            for level in 1..LEVELS {
                let near = Aabb::new(p - DVec3::splat(lat.spill), p + DVec3::splat(lat.spill));
                let borrowers = lat
                    .jobs_meeting(level, &near)
                    .into_iter()
                    .filter(|&k| lat.grow_box(k).contains(p) && may_borrow(&lat, k, p))
                    .count();
                assert!(borrowers <= 1, "{p} at level {level}: {borrowers}");
            }
        }
    }
}
