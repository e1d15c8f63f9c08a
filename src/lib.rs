//! scanmesh: out-of-core normals, neighbourhoods and surface reconstruction for
//! huge laser scans.
//!
//! One data flow serves every capability (see `ARCHITECTURE.md`):
//! ingest ([`io`]) -> point store ([`store`]) -> tiles ([`tiling`]) -> tile
//! kernel (e.g. [`normals`]) -> seam policy -> streaming writer, scheduled by
//! [`pipeline`].
#![deny(unsafe_code)]

pub mod demo;
pub mod features;
pub mod geom;
pub mod io;
pub mod memory;
pub mod mesh;
pub mod neighbours;
pub mod normals;
pub mod pipeline;
pub mod progress;
pub mod recon;
pub mod render;
pub mod spatial;
pub mod store;
pub mod synth;
pub mod tiling;
pub mod units;
