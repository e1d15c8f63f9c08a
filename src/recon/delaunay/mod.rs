//! Reconstruction from the 3-D Delaunay triangulation by local flatness
//! (paper 4, `/work/shared/papers/README.md` section 4): the triangulation
//! (`triangulation`, exact predicates with a symbolic tie-break in
//! `predicates`, insertion order in `order`, invariants in `check`),
//! the fans of nearly flat small triangles (`umbrella`, `fan`), the
//! deletion of incompatible triangles (`cleanup`), all three over one
//! point set in `select`, and the output winding (`wind`).
//!
//! Rust has no production 3-D Delaunay triangulation: the `delaunay` crate
//! is general-dimension and far too slow (about 1.7k points/s in its own
//! baseline) and `tritet` wraps TetGen's C code, so it is written here.

pub(crate) mod check;
pub(crate) mod cleanup;
pub(crate) mod fan;
pub(crate) mod holes;
pub(crate) mod kernel;
pub(crate) mod order;
pub(crate) mod patch;
pub(crate) mod pieces;
pub(crate) mod predicates;
pub mod reconstruct;
pub(crate) mod rim;
pub(crate) mod scale;
pub(crate) mod select;
pub(crate) mod triangulation;
pub(crate) mod umbrella;
pub(crate) mod wind;

#[cfg(test)]
mod exact_tests;
#[cfg(test)]
mod surface_tests;
#[cfg(test)]
mod tests;

pub use check::sanity_check;
pub use triangulation::{Cell, Delaunay, DelaunayError, INFINITE};
