//! What the CLI asks of every command's arguments: to run, and where it
//! has them, the options every processing command shares, the run
//! directory's options with the input and output, the tile stages that run
//! as separate jobs. Each command answers in its own file (one
//! `command_args!` line), so the command table in `cli/mod.rs` is one row
//! per command.

use super::{CommonArgs, RunDirArgs};
use anyhow::{bail, Result};
use scanmesh::memory::KernelCost;
use scanmesh::rundir::StageId;
use std::path::Path;

/// A command's arguments, as the CLI's table sees them.
pub trait CommandArgs {
    /// Runs the command in this process.
    fn run(self) -> Result<()>
    where
        Self: Sized;
    /// The options every processing command takes, if this one does.
    fn common(&self) -> Option<&CommonArgs> {
        None
    }
    /// The run directory's options, if this command can keep one.
    fn run_dir(&self) -> Option<&RunDirArgs> {
        None
    }
    fn run_dir_mut(&mut self) -> Option<&mut RunDirArgs> {
        None
    }
    /// Input and output of a command that can keep a run directory.
    fn paths(&self) -> Option<(&Path, &Path)> {
        None
    }
    /// The cost of the command's stage with its default parameters
    /// (`closed`: `reconstruct --closed`), if a run of it can be planned
    /// before it runs (`info --plan --command`).
    fn planned_cost(_closed: bool) -> Option<KernelCost>
    where
        Self: Sized,
    {
        None
    }
    /// The tile stages whose tiles can run as separate jobs, in order.
    fn tile_stages(&self) -> Result<Vec<StageId>> {
        bail!("--emit: this command has no tile stages that run as separate jobs yet (normals, neighbors and reconstruct have)")
    }
}

/// `command_args!(Args => run)`: a command with none of the shared
/// options; `, common`: with them; `, run_dir`: with them and a run
/// directory (fields `common`, `run`, `input`, `output`); `, run_dir
/// |a| EXPR`: and tile stages; then `, plans |closed| EXPR`: the cost
/// of its default parameters, for `info --plan`.
macro_rules! command_args {
    ($args:ty => $run:ident $(, $kind:ident $(|$a:ident| $stages:expr)?)?
        $(, plans |$c:ident| $cost:expr)?) => {
        impl super::command::CommandArgs for $args {
            fn run(self) -> anyhow::Result<()> {
                $run(self)
            }
            $($crate::cli::command::command_args!(@ $kind $(|$a| $stages)?);)?
            $(fn planned_cost($c: bool) -> Option<scanmesh::memory::KernelCost> {
                Some($cost)
            })?
        }
    };
    (@ common) => {
        fn common(&self) -> Option<&super::CommonArgs> {
            Some(&self.common)
        }
    };
    (@ run_dir $(|$a:ident| $stages:expr)?) => {
        $crate::cli::command::command_args!(@ common);
        fn run_dir(&self) -> Option<&super::RunDirArgs> {
            Some(&self.run)
        }
        fn run_dir_mut(&mut self) -> Option<&mut super::RunDirArgs> {
            Some(&mut self.run)
        }
        fn paths(&self) -> Option<(&std::path::Path, &std::path::Path)> {
            Some((&self.input, &self.output))
        }
        $(fn tile_stages(&self) -> anyhow::Result<Vec<scanmesh::rundir::StageId>> {
            let $a = self;
            $stages
        })?
    };
}
pub(crate) use command_args;
