//! The local-projection tile kernel and its seam policy (ARCHITECTURE.md,
//! "Seams, per kernel"): the growth runs as lattice jobs (`lattice.rs`,
//! `job.rs`), never per tile, so a tiled run equals an untiled one.
//!
//! A tile owns the jobs anchored at lattice points in its core (half-open,
//! so exactly one tile owns a job). An owned job needs the lower jobs
//! whose windows meet its view, and those theirs: all within a cell of
//! the anchor, so the tile runs them too (the same bytes as their owners,
//! since a job is a pure function of what it reads) and hands back only
//! its own. It asks for more margin when some job it runs would read
//! beyond the loaded region, or a point there whose list might.
//!
//! Jobs of one level run in parallel (they never meet); levels in order.

use super::job::{id_order, run_job, Buckets, JobOutput, TileView, ToLocal};
use super::lattice::{JobKey, Lattice, LEVELS};
use super::local::wanted_data;
use super::params::ProjectionParams;
use crate::geom::Aabb;
use crate::mesh::volume6;
use crate::pipeline::{KernelError, TileFault, TileKernel};
use crate::tiling::TilePoints;
use glam::DVec3;
use rayon::prelude::*;
use std::collections::{BTreeMap, BTreeSet, HashMap, HashSet};

/// What one tile contributes: its owned jobs' triangles.
#[derive(Debug, Default)]
pub struct ProjectionTile {
    /// Triangles (store indices), wound in their piece's frame.
    pub triangles: Vec<[u32; 3]>,
    /// Index into `names` of each triangle's piece.
    pub piece: Vec<u32>,
    /// Piece names (input id of the point that began them).
    pub names: Vec<u64>,
    /// Six times the signed volume of each piece's triangles here, about
    /// the store origin.
    pub volumes: Vec<f64>,
    /// Relations between pieces the owned jobs found (see `job.rs`).
    pub relations: Vec<(u64, u64, bool)>,
    /// Points processed by the owned jobs' growth.
    pub processed: u64,
    /// Jobs run (owned or not) and owned.
    pub jobs_run: u64,
    pub jobs_owned: u64,
}

pub struct ProjectionKernel {
    pub params: ProjectionParams,
    pub lattice: Lattice,
    pub initial_margin: f64,
    /// [`super::cloud::Cloud::slack`] of the store.
    pub slack: f64,
}

impl TileKernel for ProjectionKernel {
    type Output = ProjectionTile;

    fn name(&self) -> &'static str {
        "local projection"
    }

    fn margin(&self) -> f64 {
        self.initial_margin
    }

    fn run(&self, tile: &TilePoints) -> Result<ProjectionTile, KernelError> {
        let lat = &self.lattice;
        let present = present_jobs(lat, &tile.points);
        let owned: Vec<JobKey> = present
            .iter()
            .copied()
            .filter(|&k| contains_half_open(&tile.core, lat.anchor(k)))
            .collect();
        let required = self.required(tile, &owned, &present)?;
        let buckets = Buckets::new(&tile.points, lat.cell / 4.0);
        let wanted = read_points(lat, tile, &buckets, &required);
        // Every point a job reads must have the whole cloud's list.
        let (hoods, info) = wanted_data(tile, &self.params, &wanted)?;
        let (by_id, rank) = id_order(&tile.ids);
        let view = TileView {
            by_id: &by_id,
            rank: &rank,
            points: &tile.points,
            ids: &tile.ids,
            info: &info,
            hoods: &hoods,
            buckets: &buckets,
            slack: self.slack,
        };
        let mut done: BTreeMap<JobKey, JobOutput> = BTreeMap::new();
        for level in 0..LEVELS {
            let keys: Vec<JobKey> = required
                .iter()
                .copied()
                .filter(|k| k.level == level)
                .collect();
            let lower = |k: JobKey| done.get(&k);
            let outputs = keys
                .par_iter()
                .map_init(
                    || ToLocal::new(tile.points.len()),
                    |local, &k| run_job(k, lat, &view, &lower, &self.params, local),
                )
                .collect::<Vec<_>>();
            for (k, out) in keys.into_iter().zip(outputs) {
                done.insert(k, out);
            }
        }
        let jobs_run = done.len() as u64;
        let mut out = hand_over(tile, &owned, &mut done)?;
        out.jobs_run = jobs_run;
        Ok(out)
    }
}

impl ProjectionKernel {
    /// The owned jobs and every lower job they read, transitively; fails
    /// when one of them would read beyond the loaded region. Only jobs
    /// with points in their window are run (the others make nothing).
    fn required(
        &self,
        tile: &TilePoints,
        owned: &[JobKey],
        present: &BTreeSet<JobKey>,
    ) -> Result<BTreeSet<JobKey>, KernelError> {
        let lat = &self.lattice;
        let mut all: BTreeSet<JobKey> = owned.iter().copied().collect();
        for level in (1..LEVELS).rev() {
            let at: Vec<JobKey> = all.iter().copied().filter(|k| k.level == level).collect();
            for k in at {
                let view = lat.view_box(k);
                for lower in 0..level {
                    all.extend(lat.jobs_meeting(lower, &view));
                }
            }
        }
        let mut short = 0.0f64;
        for &k in &all {
            let v = lat.view_box(k);
            let lo = (tile.loaded.min - v.min).max_element();
            let hi = (v.max - tile.loaded.max).max_element();
            short = short.max(lo).max(hi);
        }
        KernelError::unless_short(short, tile.margin)?;
        all.retain(|k| present.contains(k));
        Ok(all)
    }
}

/// The jobs whose windows hold a loaded point. Neighbouring points share
/// their jobs, so each chunk keeps a set (sorting a key per point per
/// level cost a thirtieth of the run).
fn present_jobs(lat: &Lattice, points: &[DVec3]) -> BTreeSet<JobKey> {
    points
        .par_chunks(1 << 14)
        .map(|chunk| {
            let mut keys = HashSet::new();
            for &p in chunk {
                keys.extend((0..LEVELS).filter_map(|l| lat.job_of(p, l)));
            }
            keys
        })
        .reduce(HashSet::new, |mut a, b| {
            a.extend(b);
            a
        })
        .into_iter()
        .collect()
}

/// The points in the view of some job in `required`, in index order:
/// the only ones whose lists and planes a job reads.
fn read_points(
    lat: &Lattice,
    tile: &TilePoints,
    buckets: &Buckets,
    required: &BTreeSet<JobKey>,
) -> Vec<u32> {
    let keys: Vec<JobKey> = required.iter().copied().collect();
    let read = keys
        .par_iter()
        .fold(
            || (vec![false; tile.points.len()], Vec::new()),
            |(mut read, mut members), &k| {
                members.clear();
                buckets.inside(&tile.points, &lat.view_box(k), &mut members);
                members.iter().for_each(|&i| read[i as usize] = true);
                (read, members)
            },
        )
        .map(|(read, _)| read)
        .reduce_with(|mut a, b| {
            a.iter_mut().zip(b).for_each(|(x, y)| *x |= y);
            a
        })
        .unwrap_or_else(|| vec![false; tile.points.len()]);
    (0..tile.points.len() as u32)
        .filter(|&i| read[i as usize])
        .collect()
}

fn contains_half_open(core: &Aabb, p: DVec3) -> bool {
    (0..3).all(|a| p[a] >= core.min[a] && p[a] < core.max[a])
}

fn store_u32(tile: &TilePoints, i: u32) -> Result<u32, KernelError> {
    u32::try_from(tile.store_index(i as usize))
        .map_err(|_| KernelError::Failed(TileFault::IndexTooLarge))
}

/// The owned jobs' triangles in store indices, with their pieces' volumes.
fn hand_over(
    tile: &TilePoints,
    owned: &[JobKey],
    done: &mut BTreeMap<JobKey, JobOutput>,
) -> Result<ProjectionTile, KernelError> {
    let mut out = ProjectionTile::default();
    let mut dense: HashMap<u64, u32> = HashMap::new();
    for k in owned {
        let Some(job) = done.remove(k) else { continue };
        out.jobs_owned += 1;
        out.processed += job.processed;
        out.relations.extend_from_slice(&job.relations);
        // The tile's number for each of the job's pieces, looked up once
        // per piece rather than once per triangle.
        let numbers: Vec<u32> = job
            .names
            .iter()
            .map(|&name| {
                *dense.entry(name).or_insert_with(|| {
                    out.names.push(name);
                    out.volumes.push(0.0);
                    out.names.len() as u32 - 1
                })
            })
            .collect();
        for (t, &piece) in job.tris.iter().zip(&job.piece) {
            let p = numbers[piece as usize];
            out.volumes[p as usize] += volume6(&tile.points, *t, DVec3::ZERO);
            out.triangles.push([
                store_u32(tile, t[0])?,
                store_u32(tile, t[1])?,
                store_u32(tile, t[2])?,
            ]);
            out.piece.push(p);
        }
    }
    Ok(out)
}
