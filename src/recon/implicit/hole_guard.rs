//! Keeps hole patches from crossing the mesh ([`super::holes`]): the mesh
//! triangles within [`RINGS`] rings of a boundary vertex are kept as the
//! stitcher hands tiles over, and a patch triangle that meets one of them,
//! another triangle of its patch or an earlier patch (exactly:
//! [`crate::mesh::intersect`]) is banned and the least-area programme run
//! again without it.
//!
//! Why: a hole of `--closed` is where the zero set left the band, often a
//! loop that winds over the band's edge in 3-D; its least-area patch over
//! the loop's own vertices cut through the mesh next to it (1M dragon: 6
//! self-intersecting pairs, all at patches; the demo's dragon: 176).
//! The pairs found were all within two rings of the loop; once long loops
//! got more runs ([`tries_for`]), the patch of a filament's 85-edge rim
//! crossed triangles three rings away (12 pairs), so four rings are kept.
//!
//! Left out: a ring that runs into another tile is kept only as far as the
//! tile that owns the hole's vertex holds it.

use super::holes::{LoopVertex, StitchedTriangle};
use crate::mesh::intersect::{is_flat, triangles_intersect};
use glam::DVec3;
use std::collections::{HashMap, HashSet};

/// Rings of mesh triangles around a boundary vertex kept for the check.
pub const RINGS: usize = 4;

/// Runs of the least-area programme a hole of `len` vertices gets before it
/// is left open: a fixed budget of the programme's work ([`PATCH_WORK`]
/// triangle evaluations, the programme costing `len^3 / 6` a run), at least
/// [`MIN_TRIES`] and at most [`MAX_TRIES`].
///
/// Why a budget rather than a count: each run bans the triangles that
/// crossed the mesh, and a hole winding round a thin part needs many
/// (1M dragon, `--closed`: 23, 69 and 96 runs for loops of 44, 85 and 46
/// vertices, one of them the rim of a filament no patch covered in 12);
/// a long loop's run costs as much as hundreds of short ones.
pub fn tries_for(len: usize) -> usize {
    let run = (len as f64).powi(3) / 6.0;
    ((PATCH_WORK / run.max(1.0)) as usize).clamp(MIN_TRIES, MAX_TRIES)
}

/// See [`tries_for`]: 256 runs of a 100-vertex loop.
const PATCH_WORK: f64 = 256.0 * 1e6 / 6.0;
const MIN_TRIES: usize = 12;
const MAX_TRIES: usize = 256;

/// A triangle by output indices, with its corners.
pub type Placed = ([u32; 3], [DVec3; 3]);

/// Mesh triangles near boundary vertices, each with the boundary vertex it
/// was kept for (it is forgotten with that vertex).
#[derive(Default)]
pub struct NearHoles {
    kept: Vec<(u32, Placed)>,
}

impl NearHoles {
    /// Keeps the triangles of `tile` within [`RINGS`] rings of `boundary`
    /// (vertices on an edge without a twin in the tile).
    pub fn add_tile(&mut self, tile: &[StitchedTriangle], boundary: &HashSet<u32>) {
        if boundary.is_empty() {
            return;
        }
        let mut at: HashMap<u32, Vec<usize>> = HashMap::new();
        for (i, t) in tile.iter().enumerate() {
            for v in t.vertices {
                at.entry(v.0).or_default().push(i);
            }
        }
        let mut seen: HashSet<usize> = HashSet::new();
        let mut sorted: Vec<u32> = boundary.iter().copied().collect();
        sorted.sort_unstable();
        for b in sorted {
            let mut front = vec![b];
            let mut reached: HashSet<u32> = HashSet::from([b]);
            for _ in 0..RINGS {
                let mut next = Vec::new();
                for v in front {
                    for &i in at.get(&v).into_iter().flatten() {
                        if seen.insert(i) {
                            let t = &tile[i];
                            self.kept
                                .push((b, (t.vertices.map(|x| x.0), t.vertices.map(|x| x.1))));
                        }
                        let more = tile[i].vertices.map(|x| x.0);
                        next.extend(more.into_iter().filter(|x| reached.insert(*x)));
                    }
                }
                front = next;
            }
        }
    }

    /// Forgets the triangles kept for vertices `still` says are no longer
    /// on the boundary.
    pub fn retain(&mut self, still: impl Fn(u32) -> bool) {
        self.kept.retain(|(b, _)| still(*b));
    }

    /// The kept triangles with vertex `v` (repeats possible).
    pub fn triangles_at(&self, v: u32) -> Vec<[u32; 3]> {
        self.kept
            .iter()
            .map(|(_, p)| p.0)
            .filter(|t| t.contains(&v))
            .collect()
    }

    /// Adds an accepted patch, so later patches do not cross it.
    pub fn add_patch(&mut self, patch: &[Placed]) {
        self.kept.extend(patch.iter().map(|&p| (p.0[0], p)));
    }

    /// The patch triangles (indices into `patch`) that are flat or meet a
    /// kept triangle or an earlier triangle of `patch`.
    pub fn crossing(&self, patch: &[Placed]) -> Vec<usize> {
        let (lo, hi) = bounds(patch.iter().flat_map(|p| p.1));
        let near: Vec<&Placed> = self
            .kept
            .iter()
            .map(|(_, p)| p)
            .filter(|p| {
                let (a, b) = bounds(p.1);
                a.cmple(hi).all() && lo.cmple(b).all()
            })
            .collect();
        let mut bad = Vec::new();
        for (i, p) in patch.iter().enumerate() {
            let meets = |q: &Placed| triangles_intersect(p.0, &p.1, q.0, &q.1);
            if is_flat(&p.1)
                || near.iter().any(|q| meets(q))
                || patch[..i].iter().any(|q| !is_flat(&q.1) && meets(q))
            {
                bad.push(i);
            }
        }
        bad
    }
}

fn bounds(points: impl IntoIterator<Item = DVec3>) -> (DVec3, DVec3) {
    points.into_iter().fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(p), hi.max(p)),
    )
}

/// The placed triangle of loop positions `t` (indices into `lp`).
pub fn placed(lp: &[LoopVertex], t: [usize; 3]) -> Placed {
    (t.map(|i| lp[i].0), t.map(|i| lp[i].1))
}
