//! The summary lines of `curvature` and `features`, and the features'
//! JSON summary: what a run measured, found and took.

use super::curvature::CurvatureReport;
use super::extract::FeaturesReport;
use crate::summary::Summary;
use std::fmt;

impl fmt::Display for Summary<'_, CurvatureReport> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let r = self.report;
        let m = &r.meta;
        let [sparse, degenerate, ill, unoriented] = m.flagged;
        write!(
            f,
            "curvature: {} points, {} tiles ({} reloaded), d {:.4e}, {}, |k| median {:.4e} p90 {:.4e}, \
             residual RMS {:.4e} max {:.4e}, flagged: {} sparse, {} degenerate, {} ill-conditioned, \
             {} unoriented, {:.2} s, peak {} -> {}",
            m.points,
            r.tiles,
            r.run.retries,
            m.spacing,
            m.resolved,
            m.dominant_quantile(0.5),
            m.dominant_quantile(0.9),
            m.rms,
            m.max_error,
            sparse,
            degenerate,
            ill,
            unoriented,
            self.secs,
            self.peak_text(),
            self.output.display()
        )
    }
}

impl fmt::Display for Summary<'_, FeaturesReport> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let r = self.report;
        let c = &r.counts;
        write!(
            f,
            "features: {} points, {} tiles ({} reloaded), d {:.4e}, alpha {:.4e}, feature points {} ridge / {} valley \
             (of {} / {} candidates), {} polylines, {} corners, length {:.4e}, MLS residual RMS {:.4e} max {:.4e}, \
             {:.2} s (curvature {:.2} s, lines {:.2} s), peak {} -> {}",
            r.points,
            r.tiles,
            r.run.retries,
            r.curvature.spacing,
            r.params.alpha,
            c.smoothed[0],
            c.smoothed[1],
            c.candidates[0],
            c.candidates[1],
            r.polylines,
            r.corners,
            r.length,
            r.curvature.rms,
            r.curvature.max_error,
            self.secs,
            r.curvature_secs,
            r.lines_secs,
            self.peak_text(),
            self.output.display()
        )
    }
}

impl Summary<'_, FeaturesReport> {
    /// The run as a JSON document (`features --json`): the line's numbers
    /// and, per kind, the feature points found at each stage.
    pub fn json(&self) -> serde_json::Value {
        let r = self.report;
        let c = &r.counts;
        let kind = |k: usize| {
            serde_json::json!({
                "candidates": c.candidates[k],
                "enhanced": c.enhanced[k],
                "feature_points": c.smoothed[k],
                "corners": c.corners[k],
            })
        };
        serde_json::json!({
            "points": r.points,
            "tiles": r.tiles,
            "reloaded_tiles": r.run.retries,
            "spacing_d": r.curvature.spacing,
            "alpha": r.params.alpha,
            "ridge": kind(0),
            "valley": kind(1),
            "polylines": r.polylines,
            "corners": r.corners,
            "total_length": r.length,
            "mls_residual_max": r.curvature.max_error,
            "mls_residual_rms": r.curvature.rms,
            "curvature_reused": !r.computed_curvature,
            "seconds": self.secs,
            "seconds_curvature": r.curvature_secs,
            "seconds_lines": r.lines_secs,
            "peak_rss": self.peak_text(),
            "output": self.output.display().to_string(),
        })
    }
}
