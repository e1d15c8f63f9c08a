//! The outliers' summary line: how many points the rule flagged, by what
//! threshold, and what the output holds.

use super::OutlierReport;
use crate::summary::Summary;
use std::fmt;

/// An outlier pass's report with what its output holds: the line says
/// both.
#[derive(Clone, Debug)]
pub struct OutliersWritten {
    /// What the pass found.
    pub report: OutlierReport,
    /// Rows the output holds.
    pub rows: u64,
    /// Whether the outliers were left out of it (`--drop`).
    pub dropped: bool,
}

impl fmt::Display for Summary<'_, OutliersWritten> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let r = &self.report.report;
        let p = &r.params;
        let share = 100.0 * r.outliers as f64 / r.points.max(1) as f64;
        let rule = match r.not_judged == r.points {
            true => format!(": none judged, every point has fewer than {} neighbours", p.k),
            false => format!(
                " with a mean distance to their {} nearest above {:.4e} (mean {:.4e} + {} x std {:.4e}), \
                 {} not judged (fewer than {} neighbours)",
                p.k, r.threshold, r.mean, p.ratio, r.std_dev, r.not_judged, p.k
            ),
        };
        let written = match self.report.dropped {
            true => format!("{} rows written, the outliers left out", self.report.rows),
            false => format!("{} rows written", self.report.rows),
        };
        write!(
            f,
            "outliers: {} of {} points ({share:.2} %){rule}, {} tiles ({} reloaded), {written}, \
             {:.2} s, peak {} -> {}",
            r.outliers,
            r.points,
            r.run.tiles,
            r.run.retries,
            self.secs,
            self.peak_text(),
            self.output.display()
        )
    }
}
