//! Paper 4's three steps over one set of points (a tile's, or the whole
//! cloud's): the 3-D Delaunay triangulation (section 2.1), two rounds of
//! fans (section 2.2; the second inherits from the first, see [`super::fan`])
//! and the deletion of incompatible triangles (section 2.3). A pure
//! function of the points, their ids, the hole radius and the region known
//! to hold every point of the cloud inside it.

use super::cleanup::{dilate, Cleanup, CleanupReport};
use super::fan::{spacing_bounds, tri, Fan, FanScratch, Hole, Membership, Selector};
use super::holes::{patch_doubt, small_hole_patches};
use super::pieces::{drop_extra_fans, drop_small_pieces, piece_doubt};
use super::triangulation::{Delaunay, DelaunayError};
use super::umbrella::{nearest_neighbours, umbrella, Region};
use glam::DVec3;
use rayon::prelude::*;

/// Vertices per parallel job of the fan rounds.
const CHUNK: usize = 2048;

/// The selected surface of one point set.
#[derive(Debug, Default)]
pub struct Selection {
    /// Triangles, as indices into the input points, corners sorted by
    /// index, sorted.
    pub tris: Vec<[u32; 3]>,
    /// Per input point: its decisions may differ from the whole cloud's
    /// (always false when the region is everything).
    pub doubtful: Vec<bool>,
    /// Per input point: its fan closed (paper 4's interior point).
    pub interior: Vec<bool>,
    pub report: SelectionReport,
}

#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SelectionReport {
    pub duplicates: u64,
    pub cells: u64,
    pub triangulation_bytes: u64,
    pub fan_triangles: u64,
    pub cleanup: CleanupReport,
    /// Triangles added to close small holes.
    pub patches: u64,
    /// Triangles dropped as small pieces (and extra fans).
    pub floating: u64,
}

/// All fans of one round, by vertex.
struct FanSet {
    start: Vec<u32>,
    tris: Vec<[u32; 3]>,
    interior: Vec<bool>,
    proven: Vec<bool>,
}

impl FanSet {
    fn of(&self, v: u32) -> &[[u32; 3]] {
        &self.tris[self.start[v as usize] as usize..self.start[v as usize + 1] as usize]
    }

    /// Whether a fan of one of `t`'s corners selected it.
    fn membership(&self, t: [u32; 3], sel: &Selector) -> Membership {
        if t.iter()
            .any(|&v| self.proven[v as usize] && self.of(v).contains(&t))
        {
            Membership::In
        } else if t.iter().all(|&v| self.proven[v as usize]) || !sel.selectable(t) {
            Membership::Out
        } else {
            Membership::Unknown
        }
    }
}

/// Runs paper 4 on `points` (ids `ranks`).
pub fn select(
    points: &[DVec3],
    ranks: &[u64],
    hole: Hole,
    region: Region,
) -> Result<Selection, DelaunayError> {
    let n = points.len();
    let d = Delaunay::new(points, ranks)?;
    let (near, nn) = nearest_neighbours(&d);
    let nn_proven: Vec<bool> = d
        .points()
        .iter()
        .zip(&nn)
        .map(|(p, &r)| region.holds_reach(*p, r))
        .collect();
    let spacing_bound = if region.is_everything() {
        Vec::new()
    } else {
        spacing_bounds(d.points(), &near, &nn, &nn_proven, &region, hole.ceiling())
    };
    let sel = Selector {
        d: &d,
        nn: &nn,
        near: &near,
        nn_proven: &nn_proven,
        spacing_bound: &spacing_bound,
        hole,
        region,
    };
    let first = all_fans(&sel, None);
    let inherit = |t: [u32; 3]| first.membership(t, &sel);
    let second = all_fans(&sel, Some(&inherit));
    drop(first);
    let doubt = initial_doubt(&sel, &second.proven);
    // For exactness: the steps below break ties by vertex number, so
    // vertices are renumbered by input id, an order every tile agrees on
    // (the triangulation numbers them in its insertion order, which depends
    // on the tile's point set). A Hilbert order over a grid every tile
    // shares did no better (crosscaps on 6 of 12 noisy sphere and plane
    // seeds against 7 of 12 by id and 3 of 12 by insertion order: the
    // forced choices leave crosscaps whatever the order, see issue 18).
    let ids = ById::new(&d);
    let points = ids.permute(d.points());
    let interior = ids.permute(&second.interior);
    let mut tris: Vec<[u32; 3]> = second.tris.iter().map(|t| ids.relabel(*t)).collect();
    drop(second);
    tris.sort_unstable();
    tris.dedup();
    let mut report = SelectionReport {
        duplicates: d.duplicates().len() as u64,
        cells: d.cell_count() as u64,
        triangulation_bytes: d.heap_bytes() as u64,
        fan_triangles: tris.len() as u64,
        ..SelectionReport::default()
    };
    let mut doubt = ids.permute(&doubt);
    let mut cleanup = Cleanup::new(&points, tris);
    report.cleanup = cleanup.run(&interior, &mut doubt);
    let alive: Vec<[u32; 3]> = cleanup.alive_triangles().collect();
    let fans = drop_extra_fans(&alive);
    let mut kept = drop_small_pieces(&fans);
    report.floating = (alive.len() - kept.len()) as u64;
    let patches = small_hole_patches(
        &points,
        &kept,
        match hole {
            Hole::Absolute(h) => Some(h),
            Hole::Local { .. } => None,
        },
    );
    report.patches = patches.added.len() as u64;
    if !doubt.is_empty() {
        // The extra fans read the triangles at each corner: one ring over
        // the survivors keeps the doubt closed (see the stages' docs).
        dilate(&alive, &mut doubt);
        piece_doubt(&fans, &mut doubt);
        patch_doubt(&kept, &patches, &mut doubt);
    }
    kept.retain(|t| patches.dropped.binary_search(t).is_err());
    kept.extend(patches.added);
    let input: Vec<u32> = ids.order.iter().map(|&v| d.input_index(v)).collect();
    Ok(to_input(&input, &kept, &doubt, &interior, n, report))
}

/// Every fan of one round, in parallel chunks, concatenated in vertex order.
fn all_fans(sel: &Selector, inherited: Option<&(dyn Fn([u32; 3]) -> Membership + Sync)>) -> FanSet {
    let n = sel.d.vertex_count();
    let parts: Vec<Vec<Fan>> = (0..n.div_ceil(CHUNK))
        .into_par_iter()
        .map_init(FanScratch::default, |s, c| {
            let inherited = inherited.map(|f| f as &dyn Fn([u32; 3]) -> Membership);
            (c * CHUNK..((c + 1) * CHUNK).min(n))
                .map(|v| sel.fan(v as u32, inherited, s))
                .collect()
        })
        .collect();
    let mut set = FanSet {
        start: Vec::with_capacity(n + 1),
        tris: Vec::new(),
        interior: Vec::with_capacity(n),
        proven: Vec::with_capacity(n),
    };
    set.start.push(0);
    for fan in parts.into_iter().flatten() {
        set.tris.extend_from_slice(&fan.tris);
        set.start.push(set.tris.len() as u32);
        set.interior.push(fan.interior);
        set.proven.push(fan.proven);
    }
    set
}

/// Vertices whose fan is unproven, and the corners of every triangle
/// through one of them that a fan could select (the unproven fan may hold
/// it or not). Only selectable triangles count: a triangle with a larger
/// circumradius than its hole radius is in no fan, and such triangles are
/// what joins far samples in the triangulation of a surface.
fn initial_doubt(sel: &Selector, proven: &[bool]) -> Vec<bool> {
    if sel.region.is_everything() {
        return Vec::new();
    }
    let mut doubt: Vec<bool> = proven.iter().map(|p| !p).collect();
    let (mut star, mut wings) = (Vec::new(), Vec::new());
    for u in 0..proven.len() as u32 {
        if proven[u as usize] {
            continue;
        }
        umbrella(sel.d, u, &mut star, &mut wings);
        for w in &wings {
            if sel.selectable(tri(u, w.a, w.b)) {
                doubt[w.a as usize] = true;
                doubt[w.b as usize] = true;
            }
        }
    }
    doubt
}

/// Vertex numbers in input-id order: `order[k]` is the triangulation's
/// vertex of the k-th smallest id, `label[v]` the new number of vertex `v`.
struct ById {
    order: Vec<u32>,
    label: Vec<u32>,
}

impl ById {
    fn new(d: &Delaunay) -> Self {
        let ranks = d.ranks();
        let mut order: Vec<u32> = (0..d.vertex_count() as u32).collect();
        order.sort_unstable_by_key(|&v| ranks[v as usize]);
        let mut label = vec![0; order.len()];
        for (k, &v) in order.iter().enumerate() {
            label[v as usize] = k as u32;
        }
        ById { order, label }
    }

    /// Corners renumbered and sorted.
    fn relabel(&self, t: [u32; 3]) -> [u32; 3] {
        let mut u = t.map(|v| self.label[v as usize]);
        u.sort_unstable();
        u
    }

    /// A per-vertex array in the new numbering (empty stays empty).
    fn permute<T: Copy>(&self, by_vertex: &[T]) -> Vec<T> {
        if by_vertex.is_empty() {
            return Vec::new();
        }
        self.order.iter().map(|&v| by_vertex[v as usize]).collect()
    }
}

/// The surviving triangles and the vertex flags (numbered by id, `input`
/// maps them to input indices), by input index.
fn to_input(
    input: &[u32],
    kept: &[[u32; 3]],
    doubt: &[bool],
    interior: &[bool],
    n: usize,
    report: SelectionReport,
) -> Selection {
    let mut tris: Vec<[u32; 3]> = kept
        .iter()
        .map(|t| {
            let mut u = t.map(|v| input[v as usize]);
            u.sort_unstable();
            u
        })
        .collect();
    tris.sort_unstable();
    let mut out = Selection {
        tris,
        doubtful: vec![false; n],
        interior: vec![false; n],
        report,
    };
    for (v, &inside) in interior.iter().enumerate() {
        let i = input[v] as usize;
        out.doubtful[i] = doubt.get(v).copied().unwrap_or(false);
        out.interior[i] = inside;
    }
    out
}
