//! The stages a run can be planned for before anything runs (`scanmesh
//! info --plan --command`), each with the cost of its default parameters,
//! which the memory plan of a run over an input is made from
//! ([`crate::memory::PlanTable`]).

use crate::features::params::FeatureParams;
use crate::features::CurvatureParams;
use crate::memory::KernelCost;
use crate::neighbours::NeighbourParams;
use crate::normals::NormalParams;
use crate::outliers::OutlierParams;
use crate::recon::implicit::reconstruct::ImplicitParams;

/// A stage to plan, by the command that runs it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Planned {
    /// Oriented normals (`normals`).
    #[value(help = None::<&str>)]
    Normals,
    /// The implicit surface (`reconstruct`).
    #[value(help = None::<&str>)]
    Reconstruct,
    /// Neighbour lists (`neighbors`).
    #[value(help = None::<&str>)]
    Neighbors,
    /// Per-point curvature (`curvature`).
    #[value(help = None::<&str>)]
    Curvature,
    /// Feature lines (`features`).
    #[value(help = None::<&str>)]
    Features,
    /// Outlier scores (`outliers`).
    #[value(help = None::<&str>)]
    Outliers,
}

impl Planned {
    /// The stage's cost with its default parameters (`closed`: the
    /// implicit surface's closed mode, `reconstruct --closed`).
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
