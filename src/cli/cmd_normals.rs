//! `scanmesh normals`: oriented normals for every point, in input order.

use super::args::{HoodArgs, OrientArgs};
use anyhow::Result;
use clap::Args;
use scanmesh::io::not_held;
use scanmesh::normals::{compute_normals, normals_output, NormalParams};
use scanmesh::rundir::{Computing, Hear, Said, Session};
use scanmesh::spatial::KnnBackend;
use scanmesh::store::{export_points_keeping, PointStore, Rows, StageId, NORMALS};
use std::path::PathBuf;

super::command::command_args!(NormalsArgs => run, run_dir |_a| Ok(vec![StageId::NORMALS]), plans |_c| scanmesh::rundir::PointRun::cost(NormalParams::default().cost()));
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
    let params = a.params()?;
    params.validate()?;
    let mut spec = normals_output(&a.output, a.ascii)?;
    let compute = |store: &mut PointStore, c: Computing| -> Result<_> {
        // A resumed run keeps normals it finished (its store outlives it).
        let valid = store.has_column(&NORMALS);
        Session::kept_or(c.session, StageId::NORMALS, valid, || -> Result<_> {
            Ok(compute_normals(store, &params, c.opts, c.progress)?)
        })
    };
    let write = |store: &PointStore, to: &Rows, hear: &dyn Hear| -> Result<_> {
        if let Some(note) = not_held(to.output, spec.carry(store.attributes())) {
            hear.hear(Said::Note(note));
        }
        Ok(export_points_keeping(store, &spec, to)?)
    };
    let paths = (a.input.as_path(), a.output.as_path());
    a.common
        .per_point(&a.run, paths, params.cost(), compute, write, |r, _| r)
}
