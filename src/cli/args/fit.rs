//! The curvature fit's argument group (`curvature`, `features`) and its
//! mapping onto [`CurvatureParams`].

use anyhow::{anyhow, Result};
use clap::Args;
use scanmesh::features::{CurvatureParams, FitHood, FitOrientation};

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
    #[arg(long, value_enum, default_value_t = FitOrientation::SpanningTree)]
    orient: FitOrientation,
}

impl FitArgs {
    pub fn params(&self) -> Result<CurvatureParams> {
        let (hood, k, iterations) = (self.neighbours, self.k, self.max_iterations);
        CurvatureParams::fit(hood, self.radius, k, iterations, self.orient)
            .map_err(|e| anyhow!("{e}"))
    }
}
