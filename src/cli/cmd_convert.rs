//! `scanmesh convert`: any point format to any other, streaming.

use anyhow::Result;
use clap::Args;
use scanmesh::io::convert::convert_keeping;
use scanmesh::io::not_held;
use scanmesh::io::place;
use std::path::PathBuf;

super::command::command_args!(ConvertArgs => run, common);
#[derive(Args)]
pub struct ConvertArgs {
    /// Input point file.
    input: PathBuf,
    /// Output point file; its extension picks the format (.ply, .xyz, .csv, .las, .laz, .pcd,
    /// .e57: one scan). Intensity, colour, classification, return number and GPS time
    /// are carried where the output format holds them.
    output: PathBuf,
    #[command(flatten)]
    pub common: super::CommonArgs,
}

pub fn run(a: ConvertArgs) -> Result<()> {
    let s = a.common.settings()?;
    s.no_scratch_limit("convert")?;
    place::check_distinct(&a.input, &a.output)?;
    s.reclaim(&[&scanmesh::io::place::directory_of(&a.output)]);
    let progress = s.progress();
    let read = s.lib.read.clone();
    let stats = convert_keeping(&a.input, &a.output, read, s.keep_unselected, progress)?;
    s.note(not_held(&a.output, stats.dropped));
    let source = a.input.display().to_string();
    s.log
        .with(|l| l.input_skipped(&source, stats.skipped, stats.left_out));
    s.summary(s.closing(&stats, &a.output));
    Ok(())
}
