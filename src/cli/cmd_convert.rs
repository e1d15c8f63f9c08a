//! `scanmesh convert`: any point format to any other, streaming.

use anyhow::Result;
use clap::Args;
use scanmesh::io::convert::convert_keeping;
use std::path::PathBuf;
use std::time::Instant;

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
    super::check_distinct(&a.input, &a.output)?;
    s.reclaim(&[&scanmesh::io::place::directory_of(&a.output)]);
    let progress = super::progress::progress(s.quiet);
    let t0 = Instant::now();
    let read = s.read_options();
    let stats = convert_keeping(
        &a.input,
        &a.output,
        read,
        s.keep_unselected,
        progress.as_ref(),
    )?;
    super::report::unselected_kept(s.keep_unselected);
    if !stats.dropped.is_empty() && !s.quiet {
        eprintln!(
            "note: {} cannot hold the input's {}: not written",
            a.output.display(),
            stats.dropped.describe()
        );
    }
    super::report::input_skipped(
        &a.input.display().to_string(),
        stats.skipped,
        stats.left_out,
    );
    super::report::summary(format!(
        "convert: {} points ({} skipped), attributes: {}, in {:.2} s, peak {} -> {}",
        stats.points,
        stats.skipped,
        stats.carried.describe(),
        t0.elapsed().as_secs_f64(),
        super::peak(),
        a.output.display()
    ));
    Ok(())
}
