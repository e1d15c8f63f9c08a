//! The whole feature-line pass over a store: curvature (reused when the
//! store holds it for the same neighbourhood), the feature kernel over the
//! tiles, then, over every polyline in cell order, the removal of copies
//! grown on both sides of a cell face (`seams.rs`), the endpoint repair and
//! the relaxation (paper 5 section 5).

use super::curvature::{compute_curvature, CurvatureMeta};
use super::kernel::{CellLines, FeatureCounts, FeaturesKernel, FeaturesTile};
use super::lines::LineGraph;
use super::params::{FeatureParams, Resolved};
use super::repair::{repair, Cone};
use super::seams::{drop_copies, CellPolyline};
use super::{CurvatureHood, FeaturesError, CURVATURE, CURVATURE_FLAGS};
use crate::geom::LineKind;
use crate::normals::has_normals_of;
use crate::pipeline::{run_tiles, Progress, RunOptions, RunStats};
use crate::store::{spacing::ensure_spacing, PointStore};
use glam::DVec3;
use std::time::Instant;

/// What a feature run found and measured.
#[derive(Clone, Debug)]
pub struct FeaturesReport {
    /// Points of the store.
    pub points: u64,
    /// Tiles processed.
    pub tiles: usize,
    /// Tiles, retries and margins of the run.
    pub run: RunStats,
    /// What the curvature column was made with and measured.
    pub curvature: CurvatureMeta,
    /// Whether the curvature was computed (not reused from the store).
    pub computed_curvature: bool,
    /// The thresholds, in absolute units, the run used.
    pub params: Resolved,
    /// Feature points and curve sets found at each stage.
    pub counts: FeatureCounts,
    /// Connected polylines, corners and total length after repair.
    pub polylines: usize,
    /// Points where lines meet.
    pub corners: usize,
    /// Total length of the polylines, in the store's coordinate units.
    pub length: f64,
    /// Seconds: curvature (with normals when computed), lines.
    pub curvature_secs: f64,
    /// Seconds spent growing and repairing the lines.
    pub lines_secs: f64,
}

/// Feature lines of `store` (vertices relative to the store origin).
pub fn extract_lines(
    store: &mut PointStore,
    params: &FeatureParams,
    opts: RunOptions,
    progress: &dyn Progress,
) -> Result<(LineGraph, FeaturesReport), FeaturesError> {
    params.validate()?;
    let t0 = Instant::now();
    // Reused only when made with these parameters from these normals (the
    // curvature parameters name the normals' own).
    let made_by = super::curvature::provenance(&params.curvature);
    let reuse = CurvatureMeta::load(store).filter(|m| {
        m.points == store.len()
            && store.provenance(&CURVATURE) == Some(&made_by)
            && store.provenance(&CURVATURE_FLAGS) == Some(&made_by)
            && has_normals_of(store, &params.curvature.normals)
    });
    let computed_curvature = reuse.is_none();
    let meta = match reuse {
        Some(m) => m,
        None => compute_curvature(store, &params.curvature, opts, progress)?.meta,
    };
    let curvature_secs = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let resolved = params.resolve(&meta);
    let estimate = ensure_spacing(store)?;
    let reach = match resolved.hood {
        CurvatureHood::Radius(r) => r,
        // A first guess; the kernel asks for more when a point needs it.
        _ => 4.0 * estimate * 4.0,
    };
    // The crest test reads its wide ball round every class enhancement reads.
    let peak = resolved.peak.map_or(0.0, |t| t.wide);
    let kernel = FeaturesKernel {
        params: resolved,
        margin: (resolved.cell + resolved.chain() + reach.max(peak) + resolved.phi) * 1.0001
            + 1e-12,
    };
    let mut cells: Vec<CellLines> = Vec::new();
    let mut corners = Vec::new();
    let mut counts = FeatureCounts::default();
    let run = run_tiles(store, &kernel, opts, progress, |_, out: FeaturesTile| {
        cells.extend(out.cells);
        corners.extend(out.corners);
        counts.merge(&out.counts);
        Ok(())
    })?;
    // Canonical order, whatever the tiling: cells by key, corners by id.
    cells.sort_by_key(|c| (c.key, c.kind));
    corners.sort_by_key(|c| (c.0, c.1));
    let grown: Vec<CellPolyline> = cells
        .into_iter()
        .flat_map(|c| {
            c.lines.into_iter().map(move |points| CellPolyline {
                cell: c.key,
                kind: c.kind,
                points,
            })
        })
        .collect();
    let kept = drop_copies(grown, 0.5 * resolved.gamma_max);
    let polylines: Vec<(LineKind, Vec<DVec3>)> =
        kept.into_iter().map(|l| (l.kind, l.points)).collect();
    let corner_points: Vec<(LineKind, DVec3)> = corners.iter().map(|c| (c.1, c.2)).collect();
    let cone = Cone {
        length: resolved.cone_length,
        half_angle: resolved.cone_angle,
    };
    let mut graph = repair(polylines, &corner_points, cone, resolved.gamma_max);
    graph.prune(resolved.cone_length);
    graph.relax(resolved.relax_passes);
    let report = FeaturesReport {
        points: store.len(),
        tiles: store.tiles().len(),
        run,
        curvature: meta,
        computed_curvature,
        params: resolved,
        counts,
        polylines: graph.components(),
        corners: graph.corner_count(),
        length: graph.length(),
        curvature_secs,
        lines_secs: t1.elapsed().as_secs_f64(),
    };
    Ok((graph, report))
}
