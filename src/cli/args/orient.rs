//! The normals' argument groups: the tangent planes' neighbourhood
//! (`normals`, `reconstruct`), the kNN structure, and how normals get
//! their sign (`normals`).

use anyhow::{anyhow, Result};
use clap::Args;
use glam::DVec3;
use scanmesh::geom::{parse_xyz, XyzTextError};
use scanmesh::normals::{
    BadNormalParameter, EdgeCost, NormalHood, NormalsError, Orientation, OrientationChoice,
    OrientationKind, Sensor,
};
use scanmesh::spatial::HoodKind;

/// The tangent planes' neighbourhood (shared with `reconstruct`).
#[derive(Args)]
pub struct HoodArgs {
    /// Neighbourhood of the tangent planes and the spanning tree: the k
    /// nearest (paper 1), or the topological neighbours of paper 3 (mean
    /// reverse shift, k per query), which add the sparse side of a density
    /// change that the k nearest miss.
    #[arg(long, visible_alias = "neighbors", value_enum, default_value_t = HoodKind::Knn)]
    neighbours: HoodKind,
    /// Cap on reverse-shift iterations (--neighbours topological).
    #[arg(long, default_value_t = 10)]
    max_iterations: usize,
}

impl HoodArgs {
    pub fn hood(&self) -> NormalHood {
        NormalHood::of(self.neighbours, self.max_iterations)
    }
}

/// How normals get their sign, and the spanning tree's edge cost.
#[derive(Args)]
pub struct OrientArgs {
    /// How normals get their sign. `auto` (default): toward each scan's
    /// station when the input names them (E57 poses), up for aerial data
    /// (a LAS/LAZ wider than tall, or --sensor aerial) with the spanning
    /// tree past vertical, else the spanning tree.
    #[arg(long, value_enum, default_value_t = OrientationKind::Auto)]
    orient: OrientationKind,
    /// What took the scan, a hint to --orient auto: `aerial` (normals face
    /// up), `terrestrial` (never taken for aerial), `auto` (judge from the
    /// data).
    #[arg(long, value_enum, default_value_t = Sensor::Auto)]
    sensor: Sensor,
    /// Spanning-tree edge cost: `offset` (default) adds the tangent-plane
    /// offset to the paper's `1 - |ni.nj|` so the tree does not cross thin parts
    /// (for --orient sources|single-source: subtracts it from `w`).
    #[arg(long, value_enum, default_value_t = EdgeCost::TangentOffset)]
    cost: EdgeCost,
    /// Scanner position x,y,z (implies --orient viewpoint).
    #[arg(long, value_parser = parse_point)]
    viewpoint: Option<DVec3>,
    /// Source propagation threshold on |ni.nj| (--orient sources|single-source).
    #[arg(long, default_value_t = scanmesh::normals::sources::DEFAULT_TAU)]
    tau: f64,
    /// Direction x,y,z of the single source (--orient single-source).
    #[arg(long, value_parser = parse_point, default_value = "0,0,1")]
    source_direction: DVec3,
}

fn parse_point(s: &str) -> Result<DVec3, String> {
    parse_xyz(s).map_err(|e| match e {
        XyzTextError::Number(e) => format!("expected x,y,z: {e}"),
        e => e.to_string(),
    })
}

impl OrientArgs {
    /// The orientation and the edge cost the flags ask for; an error names
    /// the flags that do not go together.
    pub fn orientation(&self) -> Result<(Orientation, EdgeCost)> {
        let choice = OrientationChoice {
            kind: self.orient,
            sensor: self.sensor,
            viewpoint: self.viewpoint,
            tau: self.tau,
            direction: self.source_direction,
        };
        let orientation = choice.orientation().map_err(|e| match e {
            NormalsError::BadParameter(bad) => match bad {
                BadNormalParameter::SensorNotAuto => {
                    anyhow!("--sensor goes with --orient auto only")
                }
                BadNormalParameter::NoViewpoint => {
                    anyhow!("--orient viewpoint needs --viewpoint x,y,z")
                }
                BadNormalParameter::ViewpointNotAsked => {
                    anyhow!("--viewpoint goes with --orient viewpoint only")
                }
                BadNormalParameter::Tau(_) => anyhow!("--tau must lie in [0, 1]"),
                BadNormalParameter::Direction(_) => anyhow!("--source-direction must be non-zero"),
                _ => NormalsError::BadParameter(bad).into(),
            },
            e => e.into(),
        })?;
        Ok((orientation, self.cost))
    }
}
