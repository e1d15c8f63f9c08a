//! Oriented normals (paper 1 sections 2.2-2.4): tangent planes by PCA, then
//! orientation by a minimum spanning tree over the Riemannian graph.

pub mod eigen;
pub mod pca;
