//! The normals' summary line: what a run computed, and how many normals
//! the scan's own evidence disagrees with ("0 unoriented" must not read as
//! "all right" when they face the wrong way).

use super::NormalsReport;
use crate::summary::Summary;
use std::fmt;

impl NormalsReport {
    /// How many normals disagree with the scan's own evidence, or that
    /// the input has none.
    pub fn evidence_summary(&self) -> String {
        match self.evidence {
            Some(e) => format!(
                "{} of {} checked {} ({:.2} %)",
                e.against,
                e.checked,
                e.evidence.describe(),
                if e.checked > 0 {
                    100.0 * e.against as f64 / e.checked as f64
                } else {
                    0.0
                }
            ),
            None => "no orientation evidence in the input (no station, not aerial)".into(),
        }
    }
}

impl fmt::Display for Summary<'_, NormalsReport> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let r = self.report;
        write!(
            f,
            "normals: {} points, {} tiles ({} reloaded with a wider margin), {} degenerate, {} unoriented, {}, oriented by {}, {} components, {:.2} s, peak {} -> {}",
            r.points,
            r.tiles,
            r.run.retries,
            r.degenerate,
            r.unoriented,
            r.evidence_summary(),
            r.oriented_by.describe(),
            r.components,
            self.secs,
            self.peak_text(),
            self.output.display()
        )
    }
}
