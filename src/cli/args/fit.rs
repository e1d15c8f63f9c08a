//! The curvature fit's argument group (`curvature`, `features`) and its
//! mapping onto [`CurvatureParams`].

use anyhow::{bail, Result};
use clap::{Args, ValueEnum};
use scanmesh::features::{CurvatureParams, HoodChoice};
use scanmesh::normals::{NormalParams, Orientation};

/// The curvature fit's options (shared with `features`).
#[derive(Args, Clone)]
pub struct FitArgs {
    /// Neighbourhood of the quadratic fit: every point within --radius mean
    /// spacings (paper 5's default), the --k nearest (its choice for
    /// curvature-adaptive sampling), or paper 3's topological neighbours.
    #[arg(long, visible_alias = "neighbors", value_enum, default_value_t = FitHood::Radius)]
    neighbours: FitHood,
    /// Fit radius in mean spacings d (d = mean distance to the 6 nearest
    /// neighbours; paper: 2..4). Default: 3, widened up to 4.5 on noisy
    /// input by the normals pass's noise estimate.
    #[arg(long)]
    radius: Option<f64>,
    /// Neighbours of the fit (--neighbours knn; per query for topological).
    #[arg(long, default_value_t = 15)]
    k: usize,
    /// Cap on reverse-shift iterations (--neighbours topological).
    #[arg(long, default_value_t = 10)]
    max_iterations: usize,
    /// How normals get their sign when the input has none computed:
    /// paper 5's six sources, or the spanning tree (paper 1).
    #[arg(long, value_enum, default_value_t = FitOrient::Mst)]
    orient: FitOrient,
}

#[derive(Clone, Copy, ValueEnum)]
enum FitHood {
    Radius,
    Knn,
    Topological,
}

#[derive(Clone, Copy, ValueEnum)]
enum FitOrient {
    /// Minimum spanning tree (paper 1), the project's default.
    Mst,
    /// Paper 5's six sources.
    Sources,
}

impl FitArgs {
    pub fn params(&self) -> Result<CurvatureParams> {
        let hood = match self.neighbours {
            FitHood::Radius => match self.radius {
                Some(spacings) => HoodChoice::Radius { spacings },
                None => HoodChoice::Auto,
            },
            FitHood::Knn => HoodChoice::Knn { k: self.k },
            FitHood::Topological => HoodChoice::Topological {
                k: self.k,
                max_iterations: self.max_iterations,
            },
        };
        if let Err(e) = hood.validate() {
            bail!("{e}");
        }
        let orientation = match self.orient {
            FitOrient::Mst => Orientation::SpanningTree,
            FitOrient::Sources => Orientation::SixSources {
                tau: scanmesh::normals::sources::DEFAULT_TAU,
            },
        };
        Ok(CurvatureParams {
            hood,
            normals: NormalParams {
                orientation,
                ..NormalParams::default()
            },
        })
    }
}
