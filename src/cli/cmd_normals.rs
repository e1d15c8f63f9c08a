//! `scanmesh normals`: oriented normals for every point, in input order.

use super::args::{HoodArgs, OrientArgs};
use anyhow::{Context, Result};
use clap::Args;
use scanmesh::io::not_held;
use scanmesh::io::place;
use scanmesh::normals::{compute_normals, normals_output, NormalParams};
use scanmesh::rundir::Session;
use scanmesh::spatial::KnnBackend;
use scanmesh::store::{export_points_keeping, StageId, NORMALS};
use std::path::PathBuf;

super::command::command_args!(NormalsArgs => run, run_dir |_a| Ok(vec![StageId::NORMALS]));
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
    #[arg(long, value_enum, default_value_t = KnnBackend::Grid)]
    knn: KnnBackend,
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
            backend: self.knn,
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
    place::check_distinct(&a.input, &a.output)?;
    let mut spec = normals_output(&a.output, a.ascii)?;
    let progress = s.progress();
    let mut run = s.open_input(&a.input, &a.output, params.cost(), progress)?;
    let store = &mut run.ws.store;
    // A resumed run keeps normals it finished (its store outlives it).
    let valid = store.has_column(&NORMALS);
    let report = Session::kept_or(s.run.as_ref(), StageId::NORMALS, valid, || -> Result<_> {
        Ok(compute_normals(store, &params, run.opts, progress)?)
    })?;
    s.note(not_held(&a.output, spec.carry(store.attributes())));
    let window = run.plan.window_points;
    export_points_keeping(store, &a.output, &spec, window, s.keep(&a.input), progress)
        .with_context(|| format!("writing {}", a.output.display()))?;
    s.summary(s.closing(&report, &a.output));
    Ok(())
}
