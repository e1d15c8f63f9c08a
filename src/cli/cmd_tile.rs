//! `scanmesh tile`: build a point store once, for repeated runs.

use anyhow::{bail, Result};
use clap::Args;
use scanmesh::io::open_reader;
use scanmesh::io::{cleanup, place};
use scanmesh::normals::NormalParams;
use scanmesh::store::{build_store, spacing::ensure_spacing};
use std::path::PathBuf;
use std::time::Instant;

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
    s.init_threads();
    if a.output.exists() && std::fs::read_dir(&a.output)?.next().is_some() {
        bail!("{}: exists and is not empty", a.output.display());
    }
    place::check_writable_dir(&place::directory_of(&a.output), "output")?;
    let progress = s.progress();
    let t0 = Instant::now();
    // Removed if the build is interrupted: a store without its manifest is
    // no store.
    let building = cleanup::register(&a.output);
    let mut reader = open_reader(&a.input, s.lib.read.clone())?;
    let cost = NormalParams::default().cost();
    s.lib.check_floor(&cost)?;
    let opts = s.lib.build_options(cost);
    let mut store = match build_store(reader.as_mut(), &a.output, &opts, progress) {
        Ok(st) => st,
        Err(e) => {
            let _ = std::fs::remove_dir_all(&a.output);
            return Err(e.into());
        }
    };
    ensure_spacing(&mut store)?;
    drop(building);
    let m = &store.manifest();
    s.log
        .with(|l| l.input_skipped(&m.source, m.skipped_invalid, m.left_out));
    s.summary(super::closing(store.manifest(), t0, &a.output));
    Ok(())
}
