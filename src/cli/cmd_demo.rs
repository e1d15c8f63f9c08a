//! `scanmesh demo`: the main job on the embedded sample (points sampled from
//! the Stanford dragon with noise), checked against the truth.

use anyhow::Result;
use clap::Args;
use scanmesh::demo::dragon_scan;
use scanmesh::io::memory::MemoryReader;
use scanmesh::normals::evaluate::{accuracy, normals_in_input_order};
use scanmesh::normals::{compute_normals, NormalParams};
use scanmesh::store::{build::scratch_store_dir, build_store, export_points};
use std::path::PathBuf;
use std::time::Instant;

#[derive(Args)]
pub struct DemoArgs {
    /// Where to write the result.
    #[arg(short, long, default_value = "scanmesh-demo.ply")]
    output: PathBuf,
    /// Points to sample from the embedded dragon.
    #[arg(short, default_value_t = 200_000)]
    n: usize,
    #[command(flatten)]
    common: super::CommonArgs,
}

pub fn run(a: DemoArgs) -> Result<()> {
    let s = a.common.settings()?;
    s.init_threads();
    let t0 = Instant::now();
    let (scan, mesh, spacing) = dragon_scan(a.n, 0.1, 1)?;
    println!(
        "demo: {} points sampled from the embedded Stanford dragon ({} triangles), noise 0.1 x spacing ({:.3e})",
        scan.len(),
        mesh.faces.len(),
        spacing
    );
    let progress = super::progress::progress(s.quiet);
    let params = NormalParams::default();
    let dir = scratch_store_dir(&a.output);
    let mut reader = MemoryReader::new("embedded dragon sample", scan.points.clone(), None);
    let opts = super::cmd_tile::build_options(&s, &params);
    let result = (|| -> Result<()> {
        let mut store = build_store(&mut reader, &dir, &opts, progress.as_ref())?;
        let report = compute_normals(&mut store, &params, s.run_options(), progress.as_ref())?;
        let spec = super::cmd_normals::output_spec(&a.output, false)?;
        export_points(&store, &a.output, &spec, 1 << 20, progress.as_ref())?;
        super::cmd_normals::print_summary(&report, t0.elapsed().as_secs_f64(), &a.output);
        let acc = accuracy(&normals_in_input_order(&store)?, &scan.normals);
        println!(
            "demo: normals vs the dragon's faces: median angle {:.2} deg, 95th percentile {:.2} deg, {:.3} % oriented outward",
            acc.median_angle_deg,
            acc.p95_angle_deg,
            100.0 * acc.oriented_fraction
        );
        Ok(())
    })();
    let _ = std::fs::remove_dir_all(&dir);
    result
}
