//! Surface reconstruction kernels. [`implicit`]: signed distance on one global
//! lattice + marching cubes (paper 1). [`delaunay`]: 3-D Delaunay
//! triangulation and paper 4's local-flatness selection. [`projection`]:
//! greedy local-projection Delaunay triangulation of the points themselves
//! (paper 2).

pub mod delaunay;
pub mod implicit;
pub mod projection;
mod summary;
