//! Distances between a mesh and a reference surface or point set, for
//! `scanmesh eval`: per-point distances to a mesh, and a two-sided report
//! (mean, RMS, 95th percentile, max, Hausdorff), also in units of the
//! reference's spacing (mean nearest-neighbour distance, the convention of
//! `/work/shared/papers/README.md`; paper 5 section 8 reports max and RMS).
//!
//! Each side is measured from its vertices plus area-uniform samples (see
//! `sampling.rs`) to the other side's surface; a point-set reference is its
//! own "surface" (distance to the nearest point). Nearest-triangle queries
//! are exact (Ericson 5.1.5 under a bounding-volume hierarchy, `bvh.rs`).

pub use super::closest::{
    closest_point_on_segment, closest_point_on_triangle, point_triangle_distance2,
};

use super::nearest::{PointIndex, TriangleIndex};
use super::sampling::area_samples;
use super::Mesh;
use glam::DVec3;
use rayon::prelude::*;
use std::fmt;

/// What a mesh is compared against.
#[derive(Clone, Copy, Debug)]
pub enum Reference<'a> {
    /// A triangle mesh: distances go to its nearest triangle.
    Mesh(&'a Mesh),
    /// A point set: distances go to its nearest point.
    Points(&'a [DVec3]),
}

/// Sampling of the compared surfaces.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CompareOptions {
    /// Area-uniform samples per mesh side, beside its vertices. `None`:
    /// one per triangle, clamped to [`MIN_AUTO_SAMPLES`, `MAX_AUTO_SAMPLES`].
    pub samples: Option<usize>,
    /// Seed of the area-uniform sampling, so a comparison repeats exactly.
    pub seed: u64,
}

pub(crate) const MIN_AUTO_SAMPLES: usize = 10_000;
pub(crate) const MAX_AUTO_SAMPLES: usize = 1_000_000;

impl Default for CompareOptions {
    fn default() -> Self {
        CompareOptions {
            samples: None,
            seed: 0x5CA9_3E54,
        }
    }
}

/// Summary of a set of distances. `p95` is the nearest-rank 95th
/// percentile: the smallest value at or above 95 % of the set.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct DistanceStats {
    /// Mean distance.
    pub mean: f64,
    /// Root mean square distance.
    pub rms: f64,
    /// Nearest-rank 95th percentile.
    pub p95: f64,
    /// Nearest-rank 99.9th percentile: the tail without its last thousandth,
    /// which one feature the sampling missed (a filament, a fin) sets alone.
    pub p999: f64,
    /// Largest distance.
    pub max: f64,
}

/// One direction of a comparison.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct DirectionReport {
    /// Query points (vertices plus samples).
    pub points: u64,
    /// `None` when there are no query points or nothing to measure to.
    pub absolute: Option<DistanceStats>,
    /// `absolute` divided by the reference spacing, when that is positive.
    pub in_spacing: Option<DistanceStats>,
    /// The query point farthest from the other side (the first in query
    /// order when several are): where to look when the maximum is large.
    pub max_at: Option<[f64; 3]>,
}

/// A two-sided comparison of a mesh with a reference: distances each way and the Hausdorff distance.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct DistanceReport {
    /// From the mesh's vertices and samples to the reference.
    pub mesh_to_reference: DirectionReport,
    /// From the reference's vertices (or points) and samples to the mesh.
    pub reference_to_mesh: DirectionReport,
    /// Larger of the two maxima; `None` if either side is unmeasurable.
    pub hausdorff: Option<f64>,
    /// Mean nearest-neighbour distance of the reference's vertices/points.
    pub reference_spacing: Option<f64>,
    /// `hausdorff` divided by `reference_spacing`, when both are known.
    pub hausdorff_in_spacing: Option<f64>,
    /// Area-uniform samples taken on the mesh, besides its vertices.
    pub mesh_samples: u64,
    /// Area-uniform samples taken on the reference, besides its vertices (0 for points).
    pub reference_samples: u64,
}

/// Distance from each point to the nearest triangle of `mesh` (in parallel,
/// in input order). Infinite when the mesh has no valid triangle; NaN for a
/// non-finite point.
pub fn point_to_mesh_distances(points: &[DVec3], mesh: &Mesh) -> Vec<f64> {
    let index = TriangleIndex::new(mesh);
    points.par_iter().map(|&p| index.distance(p)).collect()
}

/// Two-sided comparison with the default options.
pub fn compare(mesh: &Mesh, reference: Reference) -> DistanceReport {
    compare_with(mesh, reference, &CompareOptions::default())
}

/// Two-sided comparison. Memory: the query points of both sides (24 B
/// each) plus one search tree at a time (about 95 B per triangle or 47 B
/// per point, see `nearest.rs`). Deterministic for a given seed, whatever
/// the thread count.
pub fn compare_with(mesh: &Mesh, reference: Reference, options: &CompareOptions) -> DistanceReport {
    let mesh_points = vertices_and_samples(mesh, options);
    let mesh_samples = mesh_points.len() - finite(&mesh.vertices).count();
    let (reference_points, reference_samples, spacing, to_reference) = match reference {
        Reference::Mesh(r) => {
            let points = vertices_and_samples(r, options);
            let samples = points.len() - finite(&r.vertices).count();
            let spacing = mean_spacing(&r.vertices);
            let index = TriangleIndex::new(r);
            let d = distances(&mesh_points, |p| index.distance(p), !index.is_empty());
            (points, samples, spacing, d)
        }
        Reference::Points(ps) => {
            let points: Vec<DVec3> = finite(ps).collect();
            let index = PointIndex::new(&points);
            let spacing = mean_spacing(&points);
            let d = distances(&mesh_points, |p| index.distance(p), index.len() > 0);
            (points, 0, spacing, d)
        }
    };
    let mesh_index = TriangleIndex::new(mesh);
    let from_reference = distances(
        &reference_points,
        |p| mesh_index.distance(p),
        !mesh_index.is_empty(),
    );
    let m2r = direction(&mesh_points, to_reference, spacing);
    let r2m = direction(&reference_points, from_reference, spacing);
    let hausdorff = match (m2r.absolute, r2m.absolute) {
        (Some(a), Some(b)) => Some(a.max.max(b.max)),
        _ => None,
    };
    DistanceReport {
        mesh_to_reference: m2r,
        reference_to_mesh: r2m,
        hausdorff,
        reference_spacing: spacing,
        hausdorff_in_spacing: hausdorff.zip(spacing).map(|(h, s)| h / s),
        mesh_samples: mesh_samples as u64,
        reference_samples: reference_samples as u64,
    }
}

fn finite(points: &[DVec3]) -> impl Iterator<Item = DVec3> + '_ {
    points.iter().copied().filter(|p| p.is_finite())
}

fn sample_count(mesh: &Mesh, options: &CompareOptions) -> usize {
    options.samples.unwrap_or_else(|| {
        mesh.triangles
            .len()
            .clamp(MIN_AUTO_SAMPLES, MAX_AUTO_SAMPLES)
    })
}

/// The finite vertices of `mesh` followed by its area samples.
fn vertices_and_samples(mesh: &Mesh, options: &CompareOptions) -> Vec<DVec3> {
    let mut points: Vec<DVec3> = finite(&mesh.vertices).collect();
    points.extend(area_samples(
        mesh,
        sample_count(mesh, options),
        options.seed,
    ));
    points
}

/// Distances from `points` to a target, or `None` when the target is empty
/// (every distance would be infinite) or there are no points.
fn distances(
    points: &[DVec3],
    distance: impl Fn(DVec3) -> f64 + Sync,
    target_exists: bool,
) -> Option<Vec<f64>> {
    (target_exists && !points.is_empty()).then(|| points.par_iter().map(|&p| distance(p)).collect())
}

/// Mean distance from each finite point to its nearest other point, summed
/// in input order; `None` with fewer than two points or a zero result (all
/// points coincide).
pub fn mean_spacing(points: &[DVec3]) -> Option<f64> {
    let points: Vec<DVec3> = finite(points).collect();
    if points.len() < 2 {
        return None;
    }
    let index = PointIndex::new(&points);
    let nn: Vec<f64> = points
        .par_iter()
        .enumerate()
        .map(|(i, &p)| index.neighbour_distance(i, p))
        .collect();
    let mean = nn.iter().sum::<f64>() / nn.len() as f64;
    (mean > 0.0).then_some(mean)
}

fn direction(points: &[DVec3], d: Option<Vec<f64>>, spacing: Option<f64>) -> DirectionReport {
    let max_at = d.as_ref().and_then(|d| {
        let at = (0..d.len()).reduce(|a, b| if d[b] > d[a] { b } else { a })?;
        points.get(at).map(|p| p.to_array())
    });
    let absolute = d.and_then(stats);
    DirectionReport {
        points: points.len() as u64,
        absolute,
        in_spacing: absolute.zip(spacing).map(|(s, h)| DistanceStats {
            mean: s.mean / h,
            rms: s.rms / h,
            p95: s.p95 / h,
            p999: s.p999 / h,
            max: s.max / h,
        }),
        max_at,
    }
}

/// Mean, RMS, nearest-rank 95th and 99.9th percentiles and max, summed in
/// input order so the result is reproducible.
pub fn stats(mut d: Vec<f64>) -> Option<DistanceStats> {
    if d.is_empty() {
        return None;
    }
    let n = d.len() as f64;
    let mean = d.iter().sum::<f64>() / n;
    let rms = (d.iter().map(|x| x * x).sum::<f64>() / n).sqrt();
    let max = d.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let mut nearest_rank = |q: f64| {
        let rank = ((q * n).ceil() as usize).clamp(1, d.len()) - 1;
        *d.select_nth_unstable_by(rank, f64::total_cmp).1
    };
    let p999 = nearest_rank(0.999);
    let p95 = nearest_rank(0.95);
    Some(DistanceStats {
        mean,
        rms,
        p95,
        p999,
        max,
    })
}

impl fmt::Display for DistanceReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write_direction(f, "mesh -> reference", &self.mesh_to_reference)?;
        write_direction(f, "reference -> mesh", &self.reference_to_mesh)?;
        match self.hausdorff {
            Some(h) => write!(f, "hausdorff          {h:.6}")?,
            None => write!(f, "hausdorff          n/a")?,
        }
        match self.hausdorff_in_spacing {
            Some(h) => writeln!(f, " ({h:.3} x spacing)")?,
            None => writeln!(f)?,
        }
        match self.reference_spacing {
            Some(s) => writeln!(f, "reference spacing  {s:.6}"),
            None => writeln!(f, "reference spacing  n/a"),
        }
    }
}

fn write_direction(f: &mut fmt::Formatter<'_>, name: &str, d: &DirectionReport) -> fmt::Result {
    let Some(s) = d.absolute else {
        return writeln!(f, "{name}  {} points, nothing to measure", d.points);
    };
    write!(
        f,
        "{name}  {} points: mean {:.6}, rms {:.6}, p95 {:.6}, p99.9 {:.6}, max {:.6}",
        d.points, s.mean, s.rms, s.p95, s.p999, s.max
    )?;
    if let Some(r) = d.in_spacing {
        write!(
            f,
            " (x spacing: mean {:.3}, p95 {:.3}, p99.9 {:.3}, max {:.3})",
            r.mean, r.p95, r.p999, r.max
        )?;
    }
    match d.max_at {
        Some([x, y, z]) => writeln!(f, "; max at ({x:.6e}, {y:.6e}, {z:.6e})"),
        None => writeln!(f),
    }
}
