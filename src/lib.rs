//! scanmesh: out-of-core normals, neighbourhoods, surfaces and feature lines
//! for huge laser scans.
//!
//! One data flow serves every capability (see `ARCHITECTURE.md`): a reader
//! ([`io`]) streams points into a point store ([`store`]), a memory-mapped
//! directory sorted into spatial tiles; a tile kernel runs on each tile with
//! an overlap margin (`tiling`, scheduled by [`pipeline`]); its seam
//! policy joins the tiles exactly; outputs stream to disk. Memory stays
//! within a budget ([`memory`]) whatever the input size.
//!
//! The types a caller needs are re-exported here. The whole flow, from an
//! in-memory PLY to oriented normals written in input order, within a
//! memory promise ([`RunSettings`]: the store's tiles and the tiles in
//! flight planned from it, as `--mem` does):
//!
//! ```
//! use scanmesh::{build_store, compute_normals, export_points, open_stream_reader};
//! use scanmesh::{Format, MemoryBudget, NoProgress, NormalParams, ReadOptions, RunSettings};
//! use scanmesh::{WriterSpec, Workspace};
//!
//! // 400 points of a 20 x 20 grid on the plane z = 0, as an ASCII PLY.
//! let mut ply = String::from("ply\nformat ascii 1.0\nelement vertex 400\n");
//! ply += "property float x\nproperty float y\nproperty float z\nend_header\n";
//! for i in 0..400 {
//!     ply += &format!("{} {} 0\n", i % 20, i / 20);
//! }
//! let dir = tempfile::tempdir()?;
//! let mut reader = open_stream_reader("grid.ply".as_ref(), std::io::Cursor::new(ply), ReadOptions::default())?;
//! // At most 64 MiB on 2 threads: tile sizes and tiles in flight follow.
//! let settings = RunSettings::new(MemoryBudget::new(64 << 20, 2));
//! let params = NormalParams::default();
//! let build = settings.build_options(params.cost());
//! let store = build_store(&mut *reader, &dir.path().join("store"), &build, &NoProgress)?;
//! let mut run = settings.prepare(Workspace::kept(store), params.cost())?;
//! let report = compute_normals(&mut run.ws.store, &params, run.opts, &NoProgress)?;
//! assert_eq!((report.points, report.degenerate), (400, 0));
//!
//! let out = dir.path().join("normals.ply");
//! let spec = WriterSpec { with_normals: true, ..WriterSpec::new(Format::PlyAscii) };
//! export_points(&run.ws.store, &out, &spec, run.plan.window_points, &NoProgress)?;
//! let text = std::fs::read_to_string(&out)?;
//! let first = text.lines().skip_while(|l| *l != "end_header").nth(1).unwrap();
//! let nz: f64 = first.split_whitespace().nth(5).unwrap().parse()?;
//! assert!((nz.abs() - 1.0).abs() < 1e-6, "a plane's normal is its axis: {first}");
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! A file goes through [`RunSettings::open`] instead, which also checks the
//! output and scratch directories and the disk plan before reading it, and
//! builds a scratch store beside the output.
//!
//! `examples/reconstruct.rs` reconstructs a mesh from a file in ten lines.
#![deny(unsafe_code)]
#![warn(missing_docs)]
#![deny(rustdoc::broken_intra_doc_links)]

pub mod demo;
pub mod features;
pub mod geom;
pub mod io;
pub mod memory;
pub mod mesh;
pub mod neighbours;
pub mod normals;
pub mod outliers;
pub mod pipeline;
pub(crate) mod progress;
pub mod recon;
pub mod render;
pub mod rng;
pub mod rundir;
pub mod runlog;
pub mod spatial;
pub mod stats;
pub mod store;
pub mod summary;
pub mod synth;
pub mod telemetry;
pub(crate) mod tiling;
pub mod units;

pub use io::{
    open_reader, open_stream_reader, read_mesh_any, Format, PointReader, ReadOptions, WriterSpec,
};
pub use memory::{MemoryBudget, MemoryPlan};
pub use normals::{compute_normals, NormalParams, NormalsReport};
pub use pipeline::{Prepared, RunOptions, RunSettings};
pub use progress::{bars, Bars, NoProgress, Progress};
pub use recon::implicit::reconstruct::{reconstruct_implicit, ImplicitParams};
pub use store::{build_store, export_points, BuildOptions, PointStore, Workspace};
