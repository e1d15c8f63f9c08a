//! Local-projection Delaunay triangulation (paper 2, Wang et al. 2007): an
//! interpolating mesh whose vertices are input points, grown greedily over
//! the surface. Each vertex's neighbours are projected on its tangent plane,
//! the ones it can see are joined to it as a fan, and the fan is made
//! Delaunay in that plane.

pub mod cloud;
pub mod fan;
pub mod frame;
pub mod grow;
pub mod kernel;
pub mod local;
pub mod orient;
pub mod params;
pub mod reconstruct;
pub mod seam;
pub mod star;
pub mod stitch;
pub mod surface;
pub mod thin;
pub mod triangulate;

pub use params::ProjectionParams;
pub use reconstruct::{reconstruct_projection, ProjectionError, ProjectionReport};
pub use triangulate::{triangulate_points, triangulate_tile};
