//! The six-source tile kernel: the pairs of every core point of a tile
//! ([`super::pairs`]: its neighbourhood within `r` or its k nearest, and its
//! `bridge_k` nearest), with the PCA normals read from the store, reduced to
//! the tile's minimum spanning forest. A pair's cost depends only on its two
//! points, so every tile that sees a pair weighs it the same, and the union
//! of the tiles' forests contains the whole cloud's forest (cycle
//! property). The kernel checks that every core point's neighbourhood lies
//! inside the loaded region and asks for a wider margin otherwise.

use super::pairs::{End, PairRule};
use super::{Neighbourhood, SourceParams};
use crate::normals::forest::{spanning_forest, Edge};
use crate::normals::kernel::store_slots;
use crate::normals::FLAG_DEGENERATE;
use crate::pipeline::{KernelError, TileKernel};
use crate::spatial::{build_index, KnnBackend, Neighbour};
use crate::store::{ColumnSpec, FLAGS, NORMALS};
use crate::tiling::{MissingColumns, TilePoints};
use glam::DVec3;

pub struct SourcesKernel {
    pub params: SourceParams,
    pub margin: f64,
}

impl TileKernel for SourcesKernel {
    /// The tile's forest, sorted by [`Edge::key`].
    type Output = Vec<Edge>;

    fn name(&self) -> &'static str {
        crate::store::StageId::ORIENT_SOURCES.name()
    }

    fn codec(&self) -> Option<crate::pipeline::Codec<Self::Output>> {
        Some(crate::pipeline::Codec::serde(|edges, _, points| {
            crate::normals::forest::edges_fit(edges, points)
        }))
    }

    fn margin(&self) -> f64 {
        self.margin
    }

    fn reads(&self) -> &[ColumnSpec] {
        &[NORMALS, FLAGS]
    }

    fn run(&self, tile: &TilePoints) -> Result<Vec<Edge>, KernelError> {
        let normals = usable_normals(tile).map_err(KernelError::failed)?;
        let index = build_index(KnnBackend::KdTree, &tile.points, &tile.ids)
            .map_err(KernelError::failed)?;
        let grid = match self.params.hood {
            Neighbourhood::Radius(r) => Some(
                super::hood::RadiusGrid::new(&tile.points, &tile.ids, r)
                    .map_err(KernelError::failed)?,
            ),
            Neighbourhood::Nearest(_) => None,
        };
        let rule = PairRule::new(&self.params);
        let mut edges = Vec::new();
        let mut found: Vec<Neighbour> = Vec::new();
        let mut short = 0.0f64;
        for i in 0..tile.n_core {
            if normals[i].is_none() {
                continue;
            }
            let room = tile.room(tile.points[i]);
            if let Some(g) = &grid {
                g.within(i, &mut found);
                short = short.max(self.radius() - room);
                // A pair of core points is added once, from its lower end.
                found.retain(|nb| nb.index as usize >= tile.n_core || nb.index as usize > i);
                self.add(tile, &normals, &rule, i, &found, &mut edges);
            }
            let k = match self.params.hood {
                Neighbourhood::Radius(_) => self.params.bridge_k,
                Neighbourhood::Nearest(k) => k,
            };
            if k > 0 {
                index.knn(tile.points[i], k, Some(i as u32), &mut found);
                short = short.max(reach(&found, k) - room);
                // Bridges within r are neighbourhood pairs already.
                let r2 = self.radius() * self.radius();
                found.retain(|nb| grid.is_none() || nb.dist2 > r2);
                self.add(tile, &normals, &rule, i, &found, &mut edges);
            }
        }
        KernelError::unless_short(short, tile.margin)?;
        Ok(store_slots(tile, spanning_forest(edges, tile.points.len())))
    }
}

impl SourcesKernel {
    fn radius(&self) -> f64 {
        match self.params.hood {
            Neighbourhood::Radius(r) => r,
            Neighbourhood::Nearest(_) => 0.0,
        }
    }

    /// Edges from core point `i` to the `found` points that have normals.
    fn add(
        &self,
        tile: &TilePoints,
        normals: &[Option<DVec3>],
        rule: &PairRule,
        i: usize,
        found: &[Neighbour],
        edges: &mut Vec<Edge>,
    ) {
        let end = |k: usize| {
            normals[k].map(|n| End {
                id: tile.ids[k] as u32,
                // A local number until the forest is found.
                slot: k as u32,
                p: tile.points[k],
                n,
            })
        };
        let Some(a) = end(i) else { return };
        for nb in found {
            let j = nb.index as usize;
            let Some(b) = end(j) else { continue };
            edges.push(rule.edge(a, b));
        }
    }
}

/// Distance to the k-th neighbour; infinite when fewer than k are loaded
/// (then only a wider region can tell whether more exist).
fn reach(found: &[Neighbour], k: usize) -> f64 {
    match found.last() {
        Some(n) if found.len() >= k => n.dist2.sqrt(),
        _ => f64::INFINITY,
    }
}

/// A loaded point's PCA normal, unless it was degenerate.
fn usable_normals(tile: &TilePoints) -> Result<Vec<Option<DVec3>>, MissingColumns> {
    let (normals, flags) = tile.oriented()?;
    Ok(normals
        .iter()
        .zip(flags)
        .map(|(n, f)| {
            let ok = f & FLAG_DEGENERATE == 0 && n.is_finite() && *n != DVec3::ZERO;
            ok.then_some(*n)
        })
        .collect())
}
