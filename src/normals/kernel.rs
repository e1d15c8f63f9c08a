//! The normals tile kernel (paper 1 sections 2.2-2.4): exact kNN (or paper
//! 3's topological neighbours, see [`super::hood`]), PCA tangent planes for
//! the core points, and the tile's minimum spanning forest of the Riemannian
//! graph (an edge from each point to each of its neighbours) for the global
//! orientation pass.
//!
//! To weigh an edge from a core point to a margin point the kernel needs the
//! margin point's normal too, so it also fits the "ring" (margin points that
//! are neighbours of core points). A ring point's neighbourhood must be loaded
//! as well, so the margin covers two neighbourhood radii; the kernel checks at
//! run time that every neighbourhood it used lies inside the loaded region and
//! asks for a wider margin otherwise.

use super::forest::{spanning_forest, Edge, LocalEdge};
use super::hood::{Hood, HoodIndex};
use super::pca::fit_plane;
use super::stats::SamplingHistograms;
use super::{EdgeCost, NormalParams, Orientation, FLAG_DEGENERATE};
use crate::pipeline::{KernelError, TileKernel};
use crate::tiling::TilePoints;
use glam::DVec3;
use rayon::prelude::*;

/// What one tile contributes.
#[derive(Debug)]
pub struct NormalsTile {
    /// Unit normals of the core points, in store order (zero when degenerate).
    pub normals: Vec<[f32; 3]>,
    pub flags: Vec<u8>,
    /// The tile's minimum spanning forest, sorted by [`Edge::key`] (empty
    /// unless orientation is by spanning tree).
    pub forest: Vec<Edge>,
    /// Nearest-neighbour distances and fit residuals of the core points.
    pub sampling: SamplingHistograms,
}

pub struct NormalsKernel {
    pub params: NormalParams,
    /// Store origin, for the viewpoint (given in absolute coordinates).
    pub origin: DVec3,
    pub initial_margin: f64,
    /// Scale of the sampling histograms (the same for every tile).
    pub histogram_scale: f64,
}

/// A fitted (and, toward a viewpoint, oriented) unit normal.
#[derive(Clone, Copy, Debug)]
struct Fitted {
    n: DVec3,
    /// RMS distance of the neighbourhood to its plane.
    residual: f64,
}

impl NormalsKernel {
    fn normal_of(&self, tile: &TilePoints, i: usize, hood: &Hood) -> Option<Fitted> {
        let fit = fit_plane(&tile.points, i, &hood.nbrs).ok()?;
        let n = fit.normal;
        let n = match self.params.orientation {
            Orientation::Viewpoint(v) if n.dot(v - self.origin - tile.points[i]) < 0.0 => -n,
            _ => n,
        };
        let residual = (fit.eigenvalues[0].max(0.0) / (hood.nbrs.len() + 1) as f64).sqrt();
        Some(Fitted { n, residual })
    }
}

impl TileKernel for NormalsKernel {
    type Output = NormalsTile;

    fn name(&self) -> &str {
        "normals"
    }

    fn margin(&self) -> f64 {
        self.initial_margin
    }

    fn run(&self, tile: &TilePoints) -> Result<NormalsTile, KernelError> {
        let index = HoodIndex::build(tile, &self.params)?;
        let core = index.hoods(tile, (0..tile.n_core).into_par_iter())?;
        check_room(&core, tile.margin)?;
        let mut normals: Vec<Option<Fitted>> = vec![None; tile.points.len()];
        let core_normals: Vec<Option<Fitted>> = core
            .par_iter()
            .enumerate()
            .map(|(i, h)| self.normal_of(tile, i, h))
            .collect();
        normals[..tile.n_core].copy_from_slice(&core_normals);
        let mut out = NormalsTile {
            normals: core_normals
                .iter()
                .map(|n| n.map_or([0.0; 3], |f| f.n.as_vec3().to_array()))
                .collect(),
            flags: core_normals
                .iter()
                .map(|n| if n.is_some() { 0 } else { FLAG_DEGENERATE })
                .collect(),
            forest: Vec::new(),
            sampling: sampling(&core, &core_normals, self.histogram_scale),
        };
        if self.params.orientation == Orientation::SpanningTree {
            self.fit_ring(&index, tile, &core, &mut normals)?;
            out.forest = tile_forest(tile, &core, &normals, self.params.cost);
        }
        Ok(out)
    }
}

impl NormalsKernel {
    /// Normals of the margin points adjacent to core points.
    fn fit_ring(
        &self,
        index: &HoodIndex,
        tile: &TilePoints,
        core: &[Hood],
        normals: &mut [Option<Fitted>],
    ) -> Result<(), KernelError> {
        let mut ring: Vec<usize> = core
            .iter()
            .flat_map(|h| h.nbrs.iter().map(|n| n.index as usize))
            .filter(|&j| j >= tile.n_core)
            .collect();
        ring.sort_unstable();
        ring.dedup();
        let hoods = index.hoods(tile, ring.par_iter().copied())?;
        check_room(&hoods, tile.margin)?;
        let fitted: Vec<Option<Fitted>> = ring
            .par_iter()
            .zip(&hoods)
            .map(|(&j, h)| self.normal_of(tile, j, h))
            .collect();
        for (&j, n) in ring.iter().zip(fitted) {
            normals[j] = n;
        }
        Ok(())
    }
}

fn sampling(core: &[Hood], fitted: &[Option<Fitted>], scale: f64) -> SamplingHistograms {
    let mut h = SamplingHistograms::new(scale);
    for (hood, f) in core.iter().zip(fitted) {
        if let Some(nb) = hood.nbrs.first() {
            h.nn.add(nb.dist2.sqrt());
        }
        if let Some(f) = f {
            h.residual.add(f.residual);
        }
    }
    h
}

/// Fails with the margin that would make every neighbourhood complete.
fn check_room(hoods: &[Hood], margin: f64) -> Result<(), KernelError> {
    let short = hoods.iter().map(|h| h.short_by).fold(0.0, f64::max);
    if short > 0.0 {
        // A little extra so rounding at the region's edge cannot loop.
        let needed = if short.is_finite() {
            (margin + short) * 1.0001 + 1e-12
        } else {
            0.0
        };
        return Err(KernelError::MarginTooSmall {
            needed: needed.max(margin * 2.0),
        });
    }
    Ok(())
}

/// See [`EdgeCost`]. Symmetric in (i, j), so both tiles that see an edge
/// weigh it the same.
fn edge_cost(cost: EdgeCost, d: DVec3, fi: &Fitted, fj: &Fitted, dot: f64) -> f64 {
    let paper = 1.0 - dot.abs();
    let (ni, nj) = (fi.n, fj.n);
    match cost {
        EdgeCost::Paper => paper,
        EdgeCost::TangentOffset => {
            let len = d.length();
            let offset = if len > 0.0 {
                (d.dot(ni).abs() + d.dot(nj).abs()) / (2.0 * len)
            } else {
                0.0
            };
            paper + offset
        }
    }
}

/// The minimum spanning forest of this tile's Riemannian-graph edges: every
/// edge from a core point to one of its neighbours (k nearest or T), both
/// with normals.
fn tile_forest(
    tile: &TilePoints,
    core: &[Hood],
    normals: &[Option<Fitted>],
    cost: EdgeCost,
) -> Vec<Edge> {
    // Sequential on purpose: a parallel collect holds the edges twice at its
    // peak (10M points, --mem 256MiB: 230 -> 267 MiB measured), and this loop
    // is a few per cent of the kernel.
    let mut edges = Vec::with_capacity(core.len() * 8);
    for i in 0..core.len() {
        edges.extend(point_edges(tile, core, normals, cost, i));
    }
    spanning_forest(edges, tile.points.len())
}

/// The Riemannian-graph edges from core point `i` to its neighbours.
fn point_edges<'a>(
    tile: &'a TilePoints,
    core: &'a [Hood],
    normals: &'a [Option<Fitted>],
    cost: EdgeCost,
    i: usize,
) -> impl Iterator<Item = LocalEdge> + 'a {
    let ni = normals[i];
    core[i].nbrs.iter().filter_map(move |nb| {
        let (ni, j) = (ni?, nb.index as usize);
        // A mutual pair of core points is added once, from its lower end.
        let mutual = j < core.len() && core[j].nbrs.iter().any(|m| m.index as usize == i);
        if mutual && j < i {
            return None;
        }
        let nj = normals[j]?;
        let dot = ni.n.dot(nj.n);
        let c = edge_cost(cost, tile.points[j] - tile.points[i], &ni, &nj, dot);
        let edge = Edge::with_cost(tile.ids[i] as u32, tile.ids[j] as u32, c, dot);
        // Local numbers in the same (id) order as the edge's ends.
        let local = if tile.ids[i] < tile.ids[j] {
            [i as u32, j as u32]
        } else {
            [j as u32, i as u32]
        };
        Some(LocalEdge { edge, local })
    })
}
