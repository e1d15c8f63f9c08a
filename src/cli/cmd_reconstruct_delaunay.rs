//! `scanmesh reconstruct --method delaunay`: paper 4's reconstruction over
//! a store, tiled and exact (see `recon::delaunay`).

use anyhow::{Context, Result};
use scanmesh::mesh::MeshFormat;
use scanmesh::recon::delaunay::reconstruct::{cost, reconstruct_delaunay, DelaunayParams};
use std::path::Path;
use std::time::Instant;

pub fn run(
    s: &super::Settings,
    input: &Path,
    output: &Path,
    format: MeshFormat,
    params: &DelaunayParams,
) -> Result<()> {
    let progress = s.progress();
    let t0 = Instant::now();
    let mut prepared = s.open_input(input, output, cost(), progress)?;
    let r = reconstruct_delaunay(
        &mut prepared.ws.store,
        params,
        output,
        format,
        prepared.opts,
        progress,
    )
    .inspect_err(|e| s.log.with(|l| l.broken_promise(e.mesh())))
    .with_context(|| format!("reconstructing {}", input.display()))?;
    s.mesh_summary(&r.audit, super::closing(&r, t0, output));
    Ok(())
}
