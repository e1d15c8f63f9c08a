//! `scanmesh reconstruct --method delaunay`: paper 4's reconstruction over
//! a store, tiled and exact (see `recon::delaunay`).

use anyhow::{bail, Result};
use scanmesh::mesh::MeshFormat;
use scanmesh::recon::delaunay::reconstruct::{
    reconstruct_delaunay, DelaunayParams, DelaunayReport, BYTES_PER_POINT,
};
use scanmesh::store::{BuildOptions, TileTarget};
use std::path::Path;
use std::time::Instant;

pub fn run(
    s: &super::Settings,
    input: &Path,
    output: &Path,
    format: MeshFormat,
    hole: Option<f64>,
) -> Result<()> {
    if let Some(h) = hole {
        if !(h.is_finite() && h > 0.0) {
            bail!("--hole {h} must be a positive finite number");
        }
    }
    let progress = super::progress::progress(s.quiet);
    let t0 = Instant::now();
    let opts = BuildOptions {
        tiles: match s.tile_points {
            Some(n) => TileTarget::Points(n),
            None => TileTarget::Budget {
                budget: s.budget(),
                bytes_per_point: BYTES_PER_POINT,
                reserved_per_point: 0,
            },
        },
        scatter_buffer: (s.mem / 8).min(64 << 20) as usize,
    };
    let mut ws = s.open_input(input, output, &opts, progress.as_ref())?;
    let params = DelaunayParams { hole };
    let r = reconstruct_delaunay(
        &mut ws.store,
        &params,
        output,
        format,
        s.run_options(),
        progress.as_ref(),
    )?;
    print_summary(
        &r,
        ws.store.len(),
        ws.store.tiles().len(),
        t0.elapsed().as_secs_f64(),
        output,
    );
    Ok(())
}

fn print_summary(r: &DelaunayReport, points: u64, tiles: usize, secs: f64, out: &Path) {
    println!(
        "reconstruct (delaunay): {points} points, {tiles} tiles ({} reloaded, margin up to {:.3e}), hole {}, {} duplicates -> {} vertices, {} triangles, {} components ({} non-orientable); deleted type 1/2/forced {}/{}/{}, {} small holes closed, {} incompatible edges left; triangulation {:.0} B/point; {secs:.2} s, peak {} -> {}",
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
        r.triangulation_bytes_per_point,
        super::peak(),
        out.display()
    );
}
