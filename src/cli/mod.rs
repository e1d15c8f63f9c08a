//! Command-line arguments (raw, as clap parses them) and their validation
//! into [`Settings`], then dispatch to one module per command.

mod cmd_convert;
mod cmd_curvature;
mod cmd_demo;
mod cmd_eval;
mod cmd_features;
mod cmd_info;
mod cmd_neighbors;
mod cmd_normals;
mod cmd_reconstruct;
mod cmd_render;
mod cmd_tile;
mod progress;

use anyhow::{bail, Context, Result};
use clap::{Args, Parser, Subcommand, ValueEnum};
use scanmesh::io::InvalidPolicy;
use scanmesh::pipeline::{MemoryBudget, Progress, RunOptions};
use scanmesh::store::build::scratch_store_dir;
use scanmesh::store::{open_input, BuildOptions, Workspace};
use std::path::Path;

#[derive(Parser)]
#[command(
    name = "scanmesh",
    version,
    about = "Normals, neighbourhoods and surfaces from huge laser scans, out of core",
    long_about = "Normals, neighbourhoods and surfaces from huge laser scans, out of core.\n\n\
        Inputs: PLY (ascii/binary, .gz), XYZ/CSV text (.gz), LAS/LAZ, or a point store \
        built by `scanmesh tile`. Memory stays within --mem whatever the input size."
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Format, point count, bounding box and spacing of a file or store.
    Info(cmd_info::InfoArgs),
    /// Convert between point formats, streaming (PLY, XYZ/CSV, LAS/LAZ).
    Convert(cmd_convert::ConvertArgs),
    /// Build a tiled point store (a directory) for repeated runs.
    Tile(cmd_tile::TileArgs),
    /// Oriented normals for every point, written in input order.
    Normals(cmd_normals::NormalsArgs),
    /// Per-point principal, mean and Gaussian curvature (paper 5), in input order.
    Curvature(cmd_curvature::CurvatureArgs),
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
}

/// Options every processing command takes.
#[derive(Args, Clone, Debug)]
pub struct CommonArgs {
    /// Peak memory (RSS) promise, e.g. 256MiB, 2GiB.
    #[arg(long, default_value = "1GiB")]
    mem: String,
    /// Worker threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
    /// Force tiles of at most this many points (tests, benches).
    #[arg(long)]
    tile_points: Option<u64>,
    /// No progress bars.
    #[arg(long, short)]
    quiet: bool,
    /// Drop points with NaN/inf coordinates (counted) instead of failing.
    #[arg(long)]
    skip_invalid: bool,
}

/// Which neighbourhood a per-point computation uses (`neighbors --neighbours`,
/// `normals --neighbours`, `reconstruct --neighbours`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum HoodKind {
    /// Paper 3's topological neighbours: mean reverse shift over an R*-tree.
    Topological,
    /// The plain k nearest neighbours.
    Knn,
}

/// Validated common options.
#[derive(Clone, Copy, Debug)]
pub struct Settings {
    pub mem: u64,
    pub threads: usize,
    pub tile_points: Option<u64>,
    pub quiet: bool,
    pub policy: InvalidPolicy,
}

impl CommonArgs {
    fn settings(&self) -> Result<Settings> {
        let mem = scanmesh::units::parse_size(&self.mem)
            .with_context(|| format!("--mem {}", self.mem))?;
        if mem < 32 << 20 {
            bail!(
                "--mem {} is below the 32MiB scanmesh needs to run",
                self.mem
            );
        }
        let threads = match self.threads {
            Some(0) => bail!("--threads must be at least 1"),
            Some(t) => t,
            None => std::thread::available_parallelism().map_or(1, |n| n.get()),
        };
        if self.tile_points == Some(0) {
            bail!("--tile-points must be at least 1");
        }
        Ok(Settings {
            mem,
            threads,
            tile_points: self.tile_points,
            quiet: self.quiet,
            policy: if self.skip_invalid {
                InvalidPolicy::Skip
            } else {
                InvalidPolicy::Reject
            },
        })
    }
}

impl Settings {
    pub fn budget(&self) -> MemoryBudget {
        MemoryBudget::new(self.mem, self.threads)
    }

    pub fn run_options(&self) -> RunOptions {
        RunOptions::new(self.threads)
    }

    /// The store to work on: `input` itself when it is one, else a scratch
    /// store beside `output` built from the input file.
    pub fn open_input(
        &self,
        input: &Path,
        output: &Path,
        opts: &BuildOptions,
        progress: &dyn Progress,
    ) -> Result<Workspace> {
        let scratch = scratch_store_dir(output);
        open_input(input, &scratch, opts, self.policy, progress)
            .with_context(|| format!("reading {}", input.display()))
    }

    /// Sizes rayon's pool once per process.
    fn init_threads(&self) {
        // Only fails when a pool exists already, which is then kept.
        let _ = rayon::ThreadPoolBuilder::new()
            .num_threads(self.threads)
            .build_global();
    }
}

pub fn run() -> Result<()> {
    let cli = Cli::parse();
    match cli.command {
        Command::Info(a) => cmd_info::run(a),
        Command::Convert(a) => cmd_convert::run(a),
        Command::Tile(a) => cmd_tile::run(a),
        Command::Normals(a) => cmd_normals::run(a),
        Command::Curvature(a) => cmd_curvature::run(a),
        Command::Features(a) => cmd_features::run(a),
        Command::Neighbors(a) => cmd_neighbors::run(a),
        Command::Reconstruct(a) => cmd_reconstruct::run(a),
        Command::Render(a) => cmd_render::run(a),
        Command::Eval(a) => cmd_eval::run(a),
        Command::Demo(a) => cmd_demo::run(a),
    }
}

/// Refuses to overwrite an input with an output.
pub fn check_distinct(input: &std::path::Path, output: &std::path::Path) -> Result<()> {
    if let (Ok(a), Ok(b)) = (input.canonicalize(), output.canonicalize()) {
        if a == b {
            bail!("{}: output would overwrite the input", output.display());
        }
    }
    Ok(())
}

pub fn peak() -> String {
    scanmesh::pipeline::peak_rss_bytes().map_or("?".into(), scanmesh::units::human_bytes)
}
