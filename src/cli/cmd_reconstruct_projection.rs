//! `scanmesh reconstruct --method projection`: paper 2's greedy
//! local-projection triangulation over a store, tiled with the seams
//! re-grown (see `recon::projection`).

use anyhow::Result;
use scanmesh::mesh::MeshFormat;
use scanmesh::recon::projection::{reconstruct_projection, ProjectionParams};
use std::path::Path;
use std::time::Instant;

pub fn run(
    s: &super::Settings,
    input: &Path,
    output: &Path,
    format: MeshFormat,
    params: &ProjectionParams,
) -> Result<()> {
    let progress = s.progress();
    let t0 = Instant::now();
    let mut prepared = s.open_input(input, output, params.cost(), progress)?;
    let r = reconstruct_projection(
        &mut prepared.ws.store,
        params,
        output,
        format,
        prepared.opts,
        progress,
    )
    .inspect_err(|e| s.log.with(|l| l.broken_promise(e.mesh())))?;
    s.mesh_summary(&r.audit, super::closing(&r, t0, output));
    Ok(())
}
