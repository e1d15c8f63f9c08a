//! `scanmesh reconstruct --method projection`: paper 2's greedy
//! local-projection triangulation over a store, tiled with the seams
//! re-grown (see `recon::projection`).

use anyhow::Result;
use scanmesh::mesh::MeshFormat;
use scanmesh::recon::projection::{reconstruct_projection, ProjectionParams, ProjectionReport};
use std::path::Path;
use std::time::Instant;

pub fn run(
    s: &super::Settings,
    input: &Path,
    output: &Path,
    format: MeshFormat,
    params: &ProjectionParams,
) -> Result<()> {
    // Checked again by the library; here before any input is read.
    params
        .validate()
        .map_err(|e| anyhow::anyhow!("--{} {}: {}", e.name.replace('_', "-"), e.value, e.why))?;
    let progress = super::progress::progress(s.quiet);
    let t0 = Instant::now();
    let mut prepared = s.open_input(input, output, params.cost(), progress.as_ref())?;
    let r = reconstruct_projection(
        &mut prepared.ws.store,
        params,
        output,
        format,
        prepared.opts,
        progress.as_ref(),
    )
    .inspect_err(|e| super::report::broken_promise(e.mesh()))?;
    print_summary(
        &r,
        prepared.ws.store.tiles().len(),
        t0.elapsed().as_secs_f64(),
        output,
    );
    Ok(())
}

pub fn print_summary(r: &ProjectionReport, tiles: usize, secs: f64, out: &Path) {
    let st = &r.stitch;
    super::report::mesh_audit(&r.audit);
    super::report::summary(format!(
        "reconstruct: {} points, {} tiles ({} reloaded), projection (paper 2), spacing {:.4e}, {} lattice jobs of cell {:.3e} ({:.2} runs each) -> {} triangles, {} pieces{}, {:.2} s, peak {} -> {}; checked: {}",
        st.vertices,
        tiles,
        r.run.retries,
        r.spacing,
        r.jobs,
        r.lattice.cell,
        r.jobs_run as f64 / r.jobs.max(1) as f64,
        st.triangles,
        st.pieces,
        left_out(st.left_out, st.contradictions),
        secs,
        super::peak(),
        out.display(),
        r.audit
    ));
}

/// " (N triangles left out where M contradicting joins ran edges twice the
/// same way)", when any were.
fn left_out(triangles: u64, contradictions: u64) -> String {
    if triangles == 0 {
        return String::new();
    }
    format!(" ({triangles} triangles left out: {contradictions} contradicting joins of pieces ran their edges twice the same way)")
}
