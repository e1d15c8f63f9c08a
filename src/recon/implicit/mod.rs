//! Implicit reconstruction (paper 1, steps 5-6): a signed distance evaluated on
//! one global lattice, polygonised by marching cubes into a mesh whose vertices
//! are keyed by global lattice edge, so tiles join without cracks.
//!
//! This layer is independent of point data: [`lattice`] (corner positions and
//! edge keys), [`mc_table`] (the generated case table) and [`polygonize`]
//! (one cube, and a reference driver over a set of cubes).

pub mod blocks;
pub(crate) mod closed;
mod closed_tile;
pub(crate) mod cover;
pub(crate) mod cubes;
pub(crate) mod dilate;
pub mod field;
pub(crate) mod follow;
pub(crate) mod kernel;
pub mod lattice;
pub mod mc_table;
pub(crate) mod mls;
pub(crate) mod owners;
pub mod polygonize;
pub mod reconstruct;
pub(crate) mod refine;
pub mod sdf;
pub(crate) mod stitch;
mod validate;
pub(crate) mod winding;

pub use lattice::{edge_from_key, edge_key, Lattice, LatticeError};
pub use polygonize::{polygonize_cube, polygonize_field, CubeVertex, IndexedMesh, MeshWelder};
