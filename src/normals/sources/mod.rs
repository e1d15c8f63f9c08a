//! Normal orientation by six sources (paper 5, "valley-ridge feature lines",
//! step 2): the points of largest and smallest x, y, z get normals along
//! +-X, +-Y, +-Z; from them the sign spreads to neighbours within `r` whose
//! normals are nearly parallel (`w = |n_i . n_j| >= tau`, tau = 0.6),
//! largest `w` first, flipping a neighbour whose normal opposes; the points
//! left are oriented by the nearest-distance rule. A single source
//! direction (e.g. +Z) serves single-sheet models such as terrain.
//!
//! - [`orient_by_sources`]: the algorithm over one cloud in memory, a pure
//!   function (`propagate` has the steps, the two spreading orders and
//!   every deviation from the paper).
//! - [`orient_store`]: the same over a store of any size, tile by tile,
//!   *exactly*: the default best-first spreading is Prim's algorithm from a
//!   root joined to the sources, so each tile keeps the minimum spanning
//!   forest of its pairs, one Kruskal pass over the union of the tiles'
//!   forests finds the same tree (ARCHITECTURE.md, normal orientation), and
//!   the tiled result equals the in-memory one bit for bit, for any tiling
//!   and thread count, given the same radius (`tiled`). The default
//!   radius comes from the kernel pass's exact mean nearest-neighbour
//!   distance, not from the store's spacing estimate, which samples tiles and so
//!   changed with the tiling (and with it the result, measured on a 1M
//!   dragon: 47 points). The issue proposed orienting each tile on
//!   its own and voting one sign per tile component through the overlaps;
//!   built and measured first, that vote carried a tile's local mistake
//!   (a front across a thin ridge, with the better path outside the tile)
//!   on to every later tile: 71.5 % of the dragon oriented like the mesh
//!   with 82 tiles against 99.37 % untiled. The spanning forest has no
//!   such failure.
//!
//! Neighbourhood radius: the paper takes r = 2..4 times the mean distance of
//! a point to its 5-7 nearest neighbours; the normals pass knows the
//! *nearest*-neighbour distances, and r = 3 mean ones ([`RADIUS_SPACINGS`])
//! holds about 10-30 points on a surface, the paper's 10-20 "fit well".

mod best_first;
mod external;
mod graph;
mod hood;
mod kernel;
mod pairs;
mod propagate;
mod seeds;
mod stacks;
mod state;
mod tiled;

pub use hood::Neighbourhood;
pub use propagate::Order;
pub use seeds::{Extreme, Extremes, Sources};
pub use tiled::{orient_store, SourceStats};

use super::{EdgeCost, NormalParams, Orientation};
use crate::spatial::IndexError;
use glam::DVec3;
use graph::Graph;
use pairs::PairRule;
use propagate::{propagate, Seed};
use state::Cloud;

/// The paper's propagation threshold.
pub const DEFAULT_TAU: f64 = 0.6;
/// Default radius in mean nearest-neighbour distances.
pub const RADIUS_SPACINGS: f64 = 3.0;

/// Parameters of the six-source (or single-source) orientation, paper 5.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SourceParams {
    /// Which extreme points seed the propagation.
    pub sources: Sources,
    /// Propagate only where `w >= tau`.
    pub tau: f64,
    /// The neighbourhood across which signs propagate.
    pub hood: Neighbourhood,
    /// With a radius neighbourhood, the nearest-distance rule also reaches
    /// this many nearest points beyond `r` (0: none).
    pub bridge_k: usize,
    /// How `w` is measured (`pairs::PairRule`).
    pub weight: EdgeCost,
    /// In which order the propagation visits points.
    pub order: Order,
}

impl SourceParams {
    /// The parameters the normals parameters ask for, with the default
    /// radius for a cloud whose mean nearest-neighbour distance is
    /// `nn`, bridges to the same k nearest as the tangent planes and the
    /// spanning tree's edge cost; `None` for other orientations.
    pub(crate) fn for_normals(params: &NormalParams, nn: f64) -> Option<Self> {
        let (sources, tau) = match params.orientation {
            Orientation::SixSources { tau } => (Sources::Six, tau),
            Orientation::SingleSource { direction, tau } => (Sources::Single(direction), tau),
            _ => return None,
        };
        Some(SourceParams {
            sources,
            tau,
            hood: Neighbourhood::Radius(RADIUS_SPACINGS * nn),
            bridge_k: params.k,
            weight: params.cost,
            order: Order::BestFirst,
        })
    }

    /// The direction that roots parts no pair reaches (+X for six sources).
    pub(crate) fn first_direction(&self) -> DVec3 {
        let d = self.sources.directions();
        d.first().copied().unwrap_or(DVec3::X)
    }

    pub(crate) fn validate(&self) -> Result<(), SourcesError> {
        if !(0.0..=1.0).contains(&self.tau) {
            return Err(SourcesError::BadTau { tau: self.tau });
        }
        if self.sources.directions().is_empty() {
            return Err(SourcesError::BadDirection);
        }
        match self.hood {
            Neighbourhood::Radius(r) if r.is_finite() && r > 0.0 => Ok(()),
            Neighbourhood::Nearest(k) if k > 0 => Ok(()),
            hood => Err(SourcesError::BadNeighbourhood { hood }),
        }
    }
}

/// Errors of the six-source orientation.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SourcesError {
    /// `tau` lies outside `[0, 1]`.
    #[error("tau {tau} lies outside [0, 1]")]
    BadTau {
        /// The value given.
        tau: f64,
    },
    /// The source direction is zero or not finite.
    #[error("the source direction must be a finite non-zero vector")]
    BadDirection,
    /// The neighbourhood is empty or of a non-finite radius.
    #[error("unusable neighbourhood {hood:?}")]
    BadNeighbourhood {
        /// The neighbourhood given.
        hood: Neighbourhood,
    },
    /// The points, normals and ids given differ in number.
    #[error("{points} points but {other} normals or ids")]
    Lengths {
        /// Points given.
        points: usize,
        /// Normals or ids given.
        other: usize,
    },
    /// An id does not fit the u32 ids the orientation uses.
    #[error("id {id}: orientation names points by u32 ids (and one more for the sources' root)")]
    IdTooLarge {
        /// The id.
        id: u64,
    },
    /// The stack order was asked of a tiled run (it runs in memory only).
    #[error("the paper's stack order runs in memory only; tiles need the best-first order")]
    StacksNotTiled,
    /// The spatial index could not be built.
    #[error(transparent)]
    Index(#[from] IndexError),
}

/// The orientation of one point: flip its (unoriented) normal or not.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PointSign {
    /// Whether the normal is to be negated.
    pub flip: bool,
    /// False only for points without a normal (nothing to orient).
    pub oriented: bool,
}

/// Orients one cloud in memory. `normals[i]` is the unit unoriented normal
/// of `points[i]` (`None` when degenerate); `ids` are the input-order ids
/// that break every tie (below `u32::MAX`).
pub fn orient_by_sources(
    points: &[DVec3],
    normals: &[Option<DVec3>],
    ids: &[u64],
    params: &SourceParams,
) -> Result<Vec<PointSign>, SourcesError> {
    params.validate()?;
    for other in [normals.len(), ids.len()] {
        if other != points.len() {
            return Err(SourcesError::Lengths {
                points: points.len(),
                other,
            });
        }
    }
    let small_ids = ids
        .iter()
        .map(|&id| u32::try_from(id).ok().filter(|&v| v < u32::MAX))
        .collect::<Option<Vec<u32>>>();
    let Some(small_ids) = small_ids else {
        let id = ids.iter().copied().max().unwrap_or(0);
        return Err(SourcesError::IdTooLarge { id });
    };
    let graph = Graph::build(points, normals, ids, params)?;
    let mut ex = Extremes::new(&params.sources);
    for (i, p) in points.iter().enumerate() {
        if normals[i].is_some() {
            ex.offer(*p, ids[i], i as u64);
        }
    }
    let seeds: Vec<Seed> = ex
        .finish()
        .iter()
        .map(|e| Seed {
            point: e.index as u32,
            direction: e.direction,
        })
        .collect();
    let cloud = Cloud {
        points,
        normals,
        ids: &small_ids,
        graph: &graph,
        rule: PairRule::new(params),
        first_direction: params.first_direction(),
    };
    Ok(propagate(&cloud, &seeds, params.order))
}
