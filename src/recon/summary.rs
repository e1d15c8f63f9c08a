//! The summary lines of the three reconstruction methods: what each did
//! to the points, the mesh it wrote, and the audit of that mesh.

use super::delaunay::reconstruct::DelaunayReport;
use super::implicit::reconstruct::ImplicitReport;
use super::projection::ProjectionReport;
use crate::summary::Summary;
use std::fmt;

impl fmt::Display for Summary<'_, ImplicitReport> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let r = self.report;
        write!(
            f,
            "reconstruct: {} points, {} tiles, rho {:.4e} ({} outliers left out), delta {:.4e}, cell {:.4e}, {} cubes -> {} vertices, {} triangles{}, {:.2} s, peak {} -> {}; checked: {}",
            r.points,
            r.run.tiles,
            r.rho,
            r.rho_outliers,
            r.delta,
            r.cell,
            r.cubes,
            r.vertices,
            r.triangles,
            implicit_changes(r),
            self.secs,
            self.peak_text(),
            self.output.display(),
            r.audit
        )
    }
}

/// " (A % of the surface closed away from the data, M triangles fewer in
/// flat blocks, P small pieces dropped)", the parts that apply.
fn implicit_changes(r: &ImplicitReport) -> String {
    let p = r.pieces;
    let mut parts = Vec::new();
    if r.away_triangles > 0 {
        let drawn = r.triangles + p.triangles_dropped;
        parts.push(format!(
            "{:.2} % of the surface closed away from the data",
            100.0 * r.away_triangles as f64 / drawn.max(1) as f64
        ));
    }
    if r.merged_triangles > 0 {
        parts.push(format!(
            "{} triangles fewer in flat blocks",
            r.merged_triangles
        ));
    }
    if p.pieces_dropped > 0 {
        parts.push(format!(
            "{} small pieces dropped ({} triangles)",
            p.pieces_dropped, p.triangles_dropped
        ));
    }
    if parts.is_empty() {
        String::new()
    } else {
        format!(" ({})", parts.join(", "))
    }
}

impl fmt::Display for Summary<'_, DelaunayReport> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let r = self.report;
        write!(
            f,
            "reconstruct (delaunay): {} points, {} tiles ({} reloaded, margin up to {:.3e}), hole {}, {} duplicates -> {} vertices, {} triangles, {} components ({} non-orientable); deleted type 1/2/forced {}/{}/{}, {} small holes closed, {} incompatible edges left, {} edges of more than two triangles mended ({} triangles left out), {} triangles cut at short twists; triangulation {:.0} B/point; {:.2} s, peak {} -> {}; checked: {}",
            r.points,
            r.run.tiles,
            r.run.retries,
            r.run.largest_margin,
            r.hole,
            r.duplicates,
            r.vertices,
            r.triangles,
            r.components,
            r.non_orientable,
            r.type1,
            r.type2,
            r.forced,
            r.patches,
            r.incompatible_left,
            r.non_manifold_mended,
            r.fins_left_out,
            r.twists_cut,
            r.triangulation_bytes_per_point,
            self.secs,
            self.peak_text(),
            self.output.display(),
            r.audit
        )
    }
}

impl fmt::Display for Summary<'_, ProjectionReport> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let r = self.report;
        let st = &r.stitch;
        write!(
            f,
            "reconstruct: {} points, {} tiles ({} reloaded), projection (paper 2), spacing {:.4e}, {} lattice jobs of cell {:.3e} ({:.2} runs each) -> {} triangles, {} pieces{}, {:.2} s, peak {} -> {}; checked: {}",
            st.vertices,
            r.run.tiles,
            r.run.retries,
            r.spacing,
            r.jobs,
            r.lattice.cell,
            r.jobs_run as f64 / r.jobs.max(1) as f64,
            st.triangles,
            st.pieces,
            projection_left_out(st.left_out, st.contradictions),
            self.secs,
            self.peak_text(),
            self.output.display(),
            r.audit
        )
    }
}

/// " (N triangles left out where M contradicting joins ran edges twice the
/// same way)", when any were.
fn projection_left_out(triangles: u64, contradictions: u64) -> String {
    if triangles == 0 {
        return String::new();
    }
    format!(" ({triangles} triangles left out: {contradictions} contradicting joins of pieces ran their edges twice the same way)")
}
