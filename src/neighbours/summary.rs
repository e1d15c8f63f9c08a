//! The neighbours' summary line: the lists' sizes and, for topological
//! neighbours, the reverse-shift iterations.

use super::NeighboursReport;
use crate::summary::Summary;
use std::fmt;

impl fmt::Display for Summary<'_, NeighboursReport> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let r = self.report;
        let st = &r.stats;
        let sizes = match (
            st.min_size(),
            st.median_size(),
            st.mean_size(),
            st.max_size(),
        ) {
            (Some(lo), Some(med), Some(mean), Some(hi)) => format!("{lo}/{med}/{mean:.1}/{hi}"),
            _ => "-".into(),
        };
        let iterations = match st.median_iterations() {
            Some(m) => format!(", iterations median {m} ({} hit the cap)", st.hit_cap()),
            None => String::new(),
        };
        write!(
            f,
            "neighbors: {} points, {} tiles ({} reloaded with a wider margin), {} k {}, size min/median/mean/max {}{}, {:.2} s, peak {} -> {}",
            r.points,
            r.tiles,
            r.run.retries,
            r.params.mode_name(),
            r.params.k(),
            sizes,
            iterations,
            self.secs,
            self.peak_text(),
            self.output.display()
        )
    }
}
