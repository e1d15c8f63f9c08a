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

use super::forest::{spanning_forest, Edge};
use super::hood::{HoodIndex, Hoods};
use super::pca::fit_plane;
use super::{EdgeCost, NormalParams, Orientation, FLAG_DEGENERATE};
use crate::pipeline::{KernelError, TileKernel};
use crate::spatial::Neighbour;
use crate::store::sampling::{SamplingHistograms, ZERO_SLOT};
use crate::tiling::TilePoints;
use glam::DVec3;

/// What one tile contributes.
#[derive(Debug, serde::Serialize, serde::Deserialize)]
pub struct NormalsTile {
    /// Unit normals of the core points, in store order (zero when degenerate).
    pub normals: Vec<[f32; 3]>,
    pub flags: Vec<u8>,
    /// The tile's minimum spanning forest, sorted by [`Edge::key`] (empty
    /// unless orientation is by spanning tree).
    pub forest: Vec<Edge>,
    /// Nearest-neighbour distances and fit residuals of the core points.
    pub sampling: SamplingHistograms,
    /// Each core point's nearest-neighbour distance as the slot the
    /// sampling histogram counted it in (spanning tree only, else empty):
    /// the orientation leaves the isolated ones out of its decisions, by a
    /// cut only the whole cloud's histogram gives (`orient::isolated`).
    pub nn_slots: Vec<u16>,
}

impl NormalsTile {
    /// Whether a saved result fits tile `t` of a store of `points` points.
    pub(crate) fn fits(&self, t: &crate::store::TileEntry, points: u64) -> bool {
        let n = t.count as usize;
        self.normals.len() == n
            && self.flags.len() == n
            && self.normals.iter().flatten().all(|v| v.is_finite())
            && (self.nn_slots.is_empty() || self.nn_slots.len() == n)
            && super::forest::edges_fit(&self.forest, points)
            && self.sampling.fits(t.count)
    }
}

/// The normals' tile kernel: the core points' normals and flags, the
/// tile's spanning forest, its sampling histograms.
pub struct NormalsKernel {
    pub(crate) params: NormalParams,
    /// Store origin, for the viewpoint (given in absolute coordinates).
    pub(crate) origin: DVec3,
    pub(crate) initial_margin: f64,
    /// The store's spacing estimate, the margin's unit (and the
    /// orientation's, after the tiles).
    pub(crate) spacing: f64,
    /// Scale of the sampling histograms (the same for every tile).
    pub(crate) histogram_scale: f64,
    /// The store's stations (relative), for [`Orientation::Stations`].
    pub(crate) stations: super::evidence::StationTable,
    /// Whether the spanning tree's union-find over every point is beyond
    /// the budget, so the orientation goes external ([`super::labels`])
    /// and the forests are packed for it.
    pub(crate) external_orientation: bool,
}

/// A fitted (and, toward a viewpoint, oriented) unit normal.
#[derive(Clone, Copy, Debug)]
struct Fitted {
    n: DVec3,
    /// RMS distance of the neighbourhood to its plane.
    residual: f64,
}

/// A core point's fit and its nearest-neighbour distance (for the
/// sampling statistics).
#[derive(Clone, Copy, Debug)]
struct CoreFit {
    fitted: Option<Fitted>,
    nn: Option<f64>,
}

impl NormalsKernel {
    fn normal_of(&self, tile: &TilePoints, i: usize, nbrs: &[Neighbour]) -> Option<Fitted> {
        let fit = fit_plane(&tile.points, i, nbrs).ok()?;
        let n = fit.normal;
        let toward = |v: DVec3| {
            if n.dot(v - tile.points[i]) < 0.0 {
                -n
            } else {
                n
            }
        };
        let n = match self.params.orientation {
            Orientation::Viewpoint(v) => toward(v - self.origin),
            // A point no station's run holds keeps the PCA sign (and is
            // counted by no check); every E57 point has its scan's.
            Orientation::Stations => self.stations.of(tile.ids[i]).map_or(n, toward),
            _ => n,
        };
        let residual = (fit.eigenvalues[0].max(0.0) / (nbrs.len() + 1) as f64).sqrt();
        Some(Fitted { n, residual })
    }

    fn core_fit(&self, tile: &TilePoints, i: usize, nbrs: &[Neighbour]) -> CoreFit {
        CoreFit {
            fitted: self.normal_of(tile, i, nbrs),
            nn: nbrs.first().map(|n| n.dist2.sqrt()),
        }
    }
}

impl TileKernel for NormalsKernel {
    type Output = NormalsTile;

    fn name(&self) -> &'static str {
        crate::store::StageId::NORMALS.name()
    }

    fn codec(&self) -> Option<crate::pipeline::Codec<Self::Output>> {
        Some(crate::pipeline::Codec::serde(NormalsTile::fits))
    }

    fn margin(&self) -> f64 {
        self.initial_margin
    }

    fn run(&self, tile: &TilePoints) -> Result<NormalsTile, KernelError> {
        let index = HoodIndex::build(tile, &self.params)?;
        let (core, fits) = index.hoods(
            tile,
            tile.n_core,
            |i| i,
            |i, nbrs| self.core_fit(tile, i, nbrs),
        )?;
        KernelError::unless_short(core.short_by, tile.margin)?;
        let mut out = NormalsTile {
            normals: fits
                .iter()
                .map(|f| f.fitted.map_or([0.0; 3], |f| f.n.as_vec3().to_array()))
                .collect(),
            flags: fits
                .iter()
                .map(|f| {
                    if f.fitted.is_some() {
                        0
                    } else {
                        FLAG_DEGENERATE
                    }
                })
                .collect(),
            forest: Vec::new(),
            sampling: sampling(&fits, self.histogram_scale),
            nn_slots: Vec::new(),
        };
        if self.params.orientation.by_tree() {
            out.nn_slots = fits
                .iter()
                .map(|f| f.nn.map_or(ZERO_SLOT, |nn| out.sampling.nn.slot(nn)))
                .collect();
            let mut normals: Vec<Option<DVec3>> = vec![None; tile.points.len()];
            for (n, f) in normals.iter_mut().zip(&fits) {
                *n = f.fitted.map(|f| f.n);
            }
            drop(fits);
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
        core: &Hoods,
        normals: &mut [Option<DVec3>],
    ) -> Result<(), KernelError> {
        let mut ring: Vec<u32> = core
            .iter()
            .flatten()
            .copied()
            .filter(|&j| j as usize >= tile.n_core)
            .collect();
        ring.sort_unstable();
        ring.dedup();
        let (hoods, fitted) = index.hoods(
            tile,
            ring.len(),
            |r| ring[r] as usize,
            |j, nbrs| self.normal_of(tile, j, nbrs).map(|f| f.n),
        )?;
        KernelError::unless_short(hoods.short_by, tile.margin)?;
        for (&j, n) in ring.iter().zip(fitted) {
            normals[j as usize] = n;
        }
        Ok(())
    }
}

fn sampling(fits: &[CoreFit], scale: f64) -> SamplingHistograms {
    let mut h = SamplingHistograms::new(scale);
    for f in fits {
        if let Some(nn) = f.nn {
            h.nn.add(nn);
        }
        if let Some(f) = f.fitted {
            h.residual.add(f.residual);
        }
    }
    h
}

/// See [`EdgeCost`]. Symmetric in (i, j), so both tiles that see an edge
/// weigh it the same.
fn edge_cost(cost: EdgeCost, d: DVec3, ni: DVec3, nj: DVec3, dot: f64) -> f64 {
    let paper = 1.0 - dot.abs();
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
    core: &Hoods,
    normals: &[Option<DVec3>],
    cost: EdgeCost,
) -> Vec<Edge> {
    // Sequential on purpose: a parallel collect holds the edges twice at its
    // peak (10M points, --mem 256MiB: 230 -> 267 MiB measured), and this loop
    // is a few per cent of the kernel.
    let mut edges = Vec::with_capacity(tile.n_core * 8);
    for i in 0..tile.n_core {
        edges.extend(point_edges(tile, core, normals, cost, i));
    }
    store_slots(tile, spanning_forest(edges, tile.points.len()))
}

/// A tile forest's slots (local numbers) turned into store indices, the
/// global union-find's slots.
pub(crate) fn store_slots(tile: &TilePoints, mut forest: Vec<Edge>) -> Vec<Edge> {
    for e in &mut forest {
        e.slots = e.slots.map(|l| tile.store_index(l as usize) as u32);
    }
    forest
}

/// The Riemannian-graph edges from core point `i` to its neighbours.
fn point_edges<'a>(
    tile: &'a TilePoints,
    core: &'a Hoods,
    normals: &'a [Option<DVec3>],
    cost: EdgeCost,
    i: usize,
) -> impl Iterator<Item = Edge> + 'a {
    let ni = normals[i];
    core.get(i).iter().filter_map(move |&j| {
        let (ni, j) = (ni?, j as usize);
        // A mutual pair of core points is added once, from its lower end.
        if j < i && j < tile.n_core && core.get(j).contains(&(i as u32)) {
            return None;
        }
        let nj = normals[j]?;
        let dot = ni.dot(nj);
        let c = edge_cost(cost, tile.points[j] - tile.points[i], ni, nj, dot);
        // Slots are local numbers until the forest is found.
        let end = |k: usize| [tile.ids[k] as u32, k as u32];
        Some(Edge::between(end(i), end(j), c, dot))
    })
}
