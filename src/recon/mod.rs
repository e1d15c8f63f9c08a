//! Surface reconstruction kernels. [`implicit`]: signed distance on one global
//! lattice + marching cubes (paper 1).

pub mod implicit;
pub mod projection;
