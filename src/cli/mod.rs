//! The command table (one row per command, its arguments' type answering
//! the rest: `command`), and the run of a command line: its report, the
//! machine's limits checked, the run directory, the `--mem` promise kept.
//! The options every command shares are `settings`'.

mod args;
mod cmd_convert;
mod cmd_curvature;
mod cmd_demo;
mod cmd_eval;
mod cmd_features;
mod cmd_info;
mod cmd_neighbors;
mod cmd_normals;
mod cmd_outliers;
mod cmd_reconstruct;
mod cmd_render;
mod cmd_run_job;
mod cmd_status;
mod cmd_tile;
mod command;
mod hints;
mod report;
mod run_in_dir;
mod settings;
mod stdout;

use settings::{mem_and_threads, shown};
pub use settings::{CommonArgs, RunDirArgs, SelectArgs};
pub use stdout::closed as stdout_closed;

use anyhow::Result;
use clap::{Parser, Subcommand};
use command::CommandArgs;
use scanmesh::io::place;
use scanmesh::memory::within_promise;
use scanmesh::pipeline::KernelCost;

#[derive(Parser)]
#[command(
    name = "scanmesh",
    version,
    about = "Normals, neighbourhoods and surfaces from huge laser scans, out of core",
    long_about = "Normals, neighbourhoods and surfaces from huge laser scans, out of core.\n\n\
        Inputs: PLY (ascii/binary, .gz), XYZ/CSV text (.gz), LAS/LAZ, PCD, E57 (all scans, or --scans), or a point store \
        built by `scanmesh tile`. Memory stays within --mem whatever the input size."
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

/// The command table: one row per command, its help and its arguments'
/// type, which answers the rest ([`command::CommandArgs`]).
macro_rules! commands {
    ($($(#[$meta:meta])* $variant:ident($args:ty),)*) => {
        #[derive(Subcommand)]
        enum Command {
            $($(#[$meta])* $variant($args),)*
        }

        impl Command {
            fn args(&self) -> &dyn CommandArgs {
                match self {
                    $(Command::$variant(a) => a,)*
                }
            }

            fn args_mut(&mut self) -> &mut dyn CommandArgs {
                match self {
                    $(Command::$variant(a) => a,)*
                }
            }

            /// Runs the command in this process.
            fn dispatch(self) -> Result<()> {
                match self {
                    $(Command::$variant(a) => a.run(),)*
                }
            }
        }

        /// The commands whose run can be planned before it runs (`info
        /// --plan --command`), by name, with their default cost.
        fn plannable() -> Vec<(String, fn(bool) -> Option<KernelCost>)> {
            let costs: Vec<fn(bool) -> Option<KernelCost>> =
                vec![$(<$args as CommandArgs>::planned_cost,)*];
            let names = [$(stringify!($variant),)*].map(kebab_case);
            names.into_iter().zip(costs).filter(|(_, cost)| cost(false).is_some()).collect()
        }
    };
}

commands! {
    /// Format, point count, bounding box and spacing of a file or store.
    Info(cmd_info::InfoArgs),
    /// Convert between point formats, streaming (PLY, XYZ/CSV, LAS/LAZ, PCD, E57).
    Convert(cmd_convert::ConvertArgs),
    /// Build a tiled point store (a directory) for repeated runs.
    Tile(cmd_tile::TileArgs),
    /// Oriented normals for every point, written in input order.
    Normals(cmd_normals::NormalsArgs),
    /// Per-point principal, mean and Gaussian curvature (paper 5), in input order.
    Curvature(cmd_curvature::CurvatureArgs),
    /// Statistical outlier scores (PCL's and Open3D's rule), outliers flagged, in input order.
    Outliers(cmd_outliers::OutliersArgs),
    /// Valley-ridge feature lines (paper 5) as polylines (.ply edges or .obj lines).
    Features(cmd_features::FeaturesArgs),
    /// Topological (paper 3) or k nearest neighbours of every point, in input order.
    #[command(visible_alias = "neighbours")]
    Neighbors(cmd_neighbors::NeighborsArgs),
    /// A triangle mesh from a point cloud (implicit: paper 1).
    Reconstruct(cmd_reconstruct::ReconstructArgs),
    /// A PNG of points, feature lines and meshes (the project's own rasteriser).
    Render(cmd_render::RenderArgs),
    /// Mesh quality, and distances to a reference mesh or point set.
    Eval(cmd_eval::EvalArgs),
    /// Run the main job on a sample embedded in the binary.
    Demo(cmd_demo::DemoArgs),
    /// Do one part of a run kept in a run directory (what --emit's
    /// scripts call on each node).
    RunJob(cmd_run_job::RunJobArgs),
    /// Stages, tiles done, failures and time left of a run directory.
    Status(cmd_status::StatusArgs),
}

/// `RunJob` as clap names its subcommand: `run-job`.
fn kebab_case(name: &str) -> String {
    let dash = |i, c: char| (i > 0 && c.is_uppercase()).then_some('-');
    let chars = name.char_indices();
    chars
        .flat_map(|(i, c)| dash(i, c).into_iter().chain(c.to_lowercase()))
        .collect()
}

/// The names of the commands `info --plan --command` can plan.
fn plannable_names() -> clap::builder::PossibleValuesParser {
    let names: Vec<String> = plannable().into_iter().map(|(name, _)| name).collect();
    names.into()
}

pub fn run() -> Result<()> {
    let cli = Cli::parse();
    let common = cli.command.args().common().cloned();
    let report = common.as_ref().and_then(|c| c.report.clone());
    if let Some(path) = &report {
        place::check_output(path)?;
    }
    // Before a run directory is made or written: a refused --mem must not
    // leave a run behind that the corrected command line then differs from.
    let emit = cli
        .command
        .args()
        .run_dir()
        .is_some_and(|r| r.emit.is_some());
    let checked = common
        .as_ref()
        .map_or(Ok(()), |c| c.check_against_this_machine(emit));
    let promised = common.as_ref().and_then(|c| c.mem_and_threads(emit).ok());
    let outcome = checked
        .and_then(|()| match cli.command {
            Command::RunJob(a) => cmd_run_job::run(a),
            Command::Status(a) => cmd_status::run(a),
            command => run_in_dir::run_in_dir(command, std::env::args().skip(1).collect()),
        })
        .map_err(hints::with_flag_hints)
        // `--mem` promises the peak RSS: a run that went over it fails,
        // though its outputs are whole.
        .and_then(|()| Ok(promised.map_or(Ok(()), |(mem, _)| within_promise(mem))?));
    if let Some(path) = &report {
        // Begun when the command line was parsed: the run's cost counts from there.
        let log = common.map(|c| c.log).unwrap_or_default();
        report::write(&log, path, &outcome)?;
    }
    outcome
}
