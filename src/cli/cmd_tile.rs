//! `scanmesh tile`: build a point store once, for repeated runs.

use anyhow::Result;
use clap::Args;
use scanmesh::normals::NormalParams;
use scanmesh::rundir::{Hear, Said};
use std::path::PathBuf;

super::command::command_args!(TileArgs => run, common);
#[derive(Args)]
pub struct TileArgs {
    /// Input point file.
    input: PathBuf,
    /// Store directory to create (must not exist, or be empty).
    #[arg(short, long)]
    output: PathBuf,
    #[command(flatten)]
    pub common: super::CommonArgs,
}

pub fn run(a: TileArgs) -> Result<()> {
    let s = a.common.settings()?;
    s.no_keep("a store of the selected points")?;
    s.no_scratch_limit("tile")?;
    // Tiles sized for the normals' cost, the commonest first run.
    let cost = NormalParams::default().cost();
    let store = s
        .lib
        .build_store_dir(&a.input, &a.output, cost, s.progress())?;
    s.hear(Said::Opened(&store));
    s.summary(s.closing(store.manifest(), &a.output));
    Ok(())
}
