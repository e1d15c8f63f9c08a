//! Surface reconstruction kernels. [`implicit`]: signed distance on one global
//! lattice + marching cubes (paper 1). [`projection`]: greedy local-projection
//! Delaunay triangulation of the points themselves (paper 2).

pub mod implicit;
pub mod projection;
