//! `info --plan --command`: the commands whose plan `info` prints, each
//! with the cost of its default parameters.

use clap::ValueEnum;
use scanmesh::features::params::FeatureParams;
use scanmesh::features::CurvatureParams;
use scanmesh::neighbours::NeighbourParams;
use scanmesh::normals::NormalParams;
use scanmesh::outliers::OutlierParams;
use scanmesh::pipeline::KernelCost;
use scanmesh::recon::implicit::reconstruct::ImplicitParams;

/// Commands `info --plan` can plan.
#[derive(Clone, Copy, ValueEnum)]
pub enum Planned {
    Normals,
    Reconstruct,
    Neighbors,
    Curvature,
    Features,
    Outliers,
}

impl Planned {
    /// The command's cost with its default parameters (`closed`:
    /// `reconstruct --closed`).
    pub fn cost(self, closed: bool) -> KernelCost {
        match self {
            Planned::Normals => NormalParams::default().cost(),
            Planned::Reconstruct => ImplicitParams {
                closed,
                ..ImplicitParams::default()
            }
            .cost(),
            Planned::Neighbors => NeighbourParams::default().cost(),
            Planned::Curvature => CurvatureParams::default().cost(),
            Planned::Features => FeatureParams::default().cost(),
            Planned::Outliers => OutlierParams::default().cost(),
        }
    }
}
