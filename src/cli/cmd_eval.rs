//! `scanmesh eval`: quality of a mesh, and its distance to a reference.

use super::stdout::outln;
use anyhow::Result;
use clap::Args;
use scanmesh::mesh::evaluate::Evaluation;
use std::path::PathBuf;

super::command::command_args!(EvalArgs => run);
#[derive(Args)]
pub struct EvalArgs {
    /// Mesh to evaluate (PLY or OBJ).
    mesh: PathBuf,
    /// Reference surface: a mesh, or a point file (distances both ways).
    #[arg(long)]
    reference: Option<PathBuf>,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
    /// With a point file as --reference: its points to compare with.
    #[command(flatten)]
    select: super::SelectArgs,
}

pub fn run(a: EvalArgs) -> Result<()> {
    let select = a.select.selection();
    let evaluation = Evaluation::of(&a.mesh, a.reference.as_deref(), &select)?;
    match a.json {
        true => outln!("{}", serde_json::to_string_pretty(&evaluation.json())?),
        false => outln!("{evaluation}"),
    }
}
