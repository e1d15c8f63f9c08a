//! `scanmesh reconstruct --method delaunay`: paper 4's reconstruction over
//! a store, tiled and exact (see `recon::delaunay`).

use anyhow::{bail, Context, Result};
use scanmesh::mesh::MeshFormat;
use scanmesh::recon::delaunay::reconstruct::{
    cost, reconstruct_delaunay, DelaunayParams, DelaunayReport,
};
use std::path::Path;
use std::time::Instant;

pub fn run(
    s: &super::Settings,
    input: &Path,
    output: &Path,
    format: MeshFormat,
    hole: Option<f64>,
) -> Result<()> {
    let params = DelaunayParams { hole };
    // Checked again by the library; here before any input is read.
    if let Err(e) = params.validate() {
        bail!("--hole: {e}");
    }
    let progress = super::progress::progress(s.quiet);
    let t0 = Instant::now();
    let mut prepared = s.open_input(input, output, cost(), progress.as_ref())?;
    let r = reconstruct_delaunay(
        &mut prepared.ws.store,
        &params,
        output,
        format,
        prepared.opts,
        progress.as_ref(),
    )
    .inspect_err(|e| super::report::broken_promise(e.mesh()))
    .with_context(|| format!("reconstructing {}", input.display()))?;
    print_summary(
        &r,
        prepared.ws.store.len(),
        prepared.ws.store.tiles().len(),
        t0.elapsed().as_secs_f64(),
        output,
    );
    Ok(())
}

fn print_summary(r: &DelaunayReport, points: u64, tiles: usize, secs: f64, out: &Path) {
    super::report::mesh_audit(&r.audit);
    super::report::summary(format!(
        "reconstruct (delaunay): {points} points, {tiles} tiles ({} reloaded, margin up to {:.3e}), hole {}, {} duplicates -> {} vertices, {} triangles, {} components ({} non-orientable); deleted type 1/2/forced {}/{}/{}, {} small holes closed, {} incompatible edges left, {} edges of more than two triangles mended ({} triangles left out); triangulation {:.0} B/point; {secs:.2} s, peak {} -> {}; checked: {}",
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
        r.triangulation_bytes_per_point,
        super::peak(),
        out.display(),
        r.audit
    ));
}
