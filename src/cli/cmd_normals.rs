//! `scanmesh normals`: oriented normals for every point, in input order.

use super::args::{HoodArgs, Knn, OrientArgs};
use anyhow::{Context, Result};
use clap::Args;
use scanmesh::io::not_held;
use scanmesh::normals::{compute_normals, normals_output, NormalParams, NormalsReport};
use scanmesh::store::{export_points_keeping, StageId, NORMALS};
use std::path::PathBuf;
use std::time::Instant;

super::command::command_args!(NormalsArgs => run, run_dir |_a| Ok(vec![StageId::Normals]));
#[derive(Args)]
pub struct NormalsArgs {
    /// Input point file or store directory.
    pub input: PathBuf,
    /// Output point file: .ply (binary; --ascii for text), .xyz, .csv,
    /// .las, .laz or .pcd, normals as that format keeps them.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Neighbours per point (paper: 8..15).
    #[arg(long, default_value_t = 12)]
    k: usize,
    /// kNN structure.
    #[arg(long, value_enum, default_value_t = Knn::Grid)]
    knn: Knn,
    #[command(flatten)]
    hood: HoodArgs,
    #[command(flatten)]
    orient: OrientArgs,
    /// Write PLY as ASCII instead of binary.
    #[arg(long)]
    ascii: bool,
    #[command(flatten)]
    pub common: super::CommonArgs,
    #[command(flatten)]
    pub run: super::RunDirArgs,
}

impl NormalsArgs {
    fn params(&self) -> Result<NormalParams> {
        let (orientation, cost) = self.orient.orientation()?;
        Ok(NormalParams {
            k: self.k,
            backend: self.knn.into(),
            neighbourhood: self.hood.hood(),
            orientation,
            cost,
        })
    }
}

pub fn run(a: NormalsArgs) -> Result<()> {
    let s = a.common.settings_in(&a.run)?;
    let params = a.params()?;
    params.validate()?;
    s.init_threads();
    super::check_distinct(&a.input, &a.output)?;
    let mut spec = normals_output(&a.output, a.ascii)?;
    let progress = s.progress();
    let t0 = Instant::now();
    let mut run = s.open_input(&a.input, &a.output, params.cost(), progress)?;
    let store = &mut run.ws.store;
    // A resumed run keeps normals it finished (its store outlives it).
    let kept = match &s.run {
        Some(r) => r.run().stage::<NormalsReport>(StageId::Normals)?,
        None => None,
    };
    let report = match kept {
        Some(report) if store.has_column(&NORMALS) => report,
        _ => {
            let report = compute_normals(store, &params, run.opts, progress)?;
            if let Some(r) = &s.run {
                r.run().keep_stage(StageId::Normals, &report)?;
            }
            report
        }
    };
    s.note(not_held(&a.output, spec.carry(store.attributes())));
    let window = run.plan.window_points;
    export_points_keeping(store, &a.output, &spec, window, s.keep(&a.input), progress)
        .with_context(|| format!("writing {}", a.output.display()))?;
    s.summary(super::closing(&report, t0, &a.output));
    Ok(())
}
