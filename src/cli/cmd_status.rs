//! `scanmesh status DIR`: what a run directory holds (the run, the store,
//! whether a process works in it, each tile stage's tiles done and the
//! time left, the output, the failures in its log), as the library's
//! [`RunStatus`] computes it. It only reads, so it works while jobs run.

use super::stdout::outln;
use anyhow::{bail, Result};
use clap::Args;
use scanmesh::rundir::{RunDir, RunStatus};
use std::path::PathBuf;

super::command::command_args!(StatusArgs => run);
#[derive(Args)]
pub struct StatusArgs {
    /// Run directory.
    dir: PathBuf,
}

pub fn run(a: StatusArgs) -> Result<()> {
    let Some(status) = RunStatus::of(&RunDir::at(&a.dir)?)? else {
        bail!("{}: not a run directory", a.dir.display());
    };
    outln!("{status}")
}
