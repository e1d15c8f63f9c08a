//! The Delaunay-reconstruction tile kernel: paper 4 ([`super::select`]) on
//! a tile's core and margin points, keeping the triangles the tile owns.
//!
//! Seam policy (ARCHITECTURE.md, interpolating meshes): vertices are the
//! input points, addressed by store index; a triangle belongs to the tile
//! whose core holds its corner of smallest input id, so each is written
//! once. It is exact: every choice the kernel makes for an owned triangle
//! is proven to be the whole cloud's (a triangle's empty sphere lies in the
//! loaded region or the store shows it empty beyond, see
//! [`super::umbrella`]; doubt spreads as far as the
//! deletion rounds can carry it, see [`super::cleanup`]); a tile with a
//! doubtful core point asks for a wider margin.
//!
//! Winding is global (a component may cross many tiles), so the kernel
//! winds its own triangles ([`super::wind`]), numbers their components, and
//! lists its seam edges: edges of an owned triangle that one other triangle
//! of the cloud shares, owned by another tile. The stitcher pairs them
//! across tiles. An edge's order is the cloud's: every triangle on it has
//! one of its corners, and a triangle with a sure corner is the cloud's
//! (a tile whose owned triangle has an edge between two doubtful corners
//! asks for a wider margin).

use super::fan::Hole;
use super::select::{select, SelectionReport};
use super::umbrella::Region;
use super::wind::wind_beside;
use crate::mesh::volume6;
use crate::pipeline::{KernelError, TileKernel};
use crate::store::PointStore;
use crate::tiling::{Beyond, TilePoints};
use glam::DVec3;

/// Kernel bytes per loaded point, for tile sizing: the triangulation's
/// ~265 B (measured on the 1M dragon), two rounds of fans, the deletion's
/// edge index, the tile's own columns; rounded up from the 800 B the 1M
/// untiled run shows, for the points a tile waiting for memory holds, the
/// seam side, and the store points the proofs read beyond the tile
/// (`tiling::Beyond`: 24 B each, at most a shell of twice the margin).
/// The 3M noisy dragon under `--mem 768MiB` still peaks at 867 MiB: freed
/// tile memory stays in the workers' allocator arenas (ARCHITECTURE.md,
/// memory model).
pub(crate) const BYTES_PER_POINT: u64 = 1000;

/// One tile's share of the surface.
#[derive(Debug, Default)]
pub struct DelaunayTile {
    /// Owned triangles, wound, as store indices.
    pub tris: Vec<[u64; 3]>,
    /// Tile-local component of each triangle.
    pub component: Vec<u32>,
    /// Per tile-local component: it could not be wound consistently.
    pub inconsistent: Vec<bool>,
    /// Per tile-local component: six times the signed volume of its owned
    /// triangles as wound, about the store origin (the seam side turns
    /// each whole component to a positive sum).
    pub volumes: Vec<f64>,
    /// Edges no other owned triangle shares (another tile's triangle may,
    /// or none): `(a, b)` as wound in the owned triangle (store indices),
    /// and its component.
    pub seams: Vec<(u64, u64, u32)>,
    pub report: SelectionReport,
}

pub struct DelaunayKernel<'a> {
    pub hole: Hole,
    pub initial_margin: f64,
    /// The store, for proofs whose spheres poke out of a tile's loaded
    /// region (`tiling::Beyond`); `None` proves inside the region only.
    pub store: Option<&'a PointStore>,
}

impl TileKernel for DelaunayKernel<'_> {
    type Output = DelaunayTile;

    fn name(&self) -> &str {
        "delaunay surface"
    }

    fn margin(&self) -> f64 {
        self.initial_margin
    }

    /// The doubt's depth varies by tile (a reload may load six times the
    /// core), so reloads wait for memory (`pipeline::shares`).
    fn bytes_per_loaded_point(&self) -> Option<u64> {
        Some(BYTES_PER_POINT)
    }

    fn run(&self, tile: &TilePoints) -> Result<DelaunayTile, KernelError> {
        // Proofs may read as far beyond the region again as twice its
        // margin: the widest empty spheres met (115 spacings across, at the
        // first margin of 110) need that, and the points read stay a shell
        // round the tile, kept at 24 B each (at most about 6 % of the
        // kernel's bytes; reading without bounds kept most of the store).
        let beyond = self
            .store
            .map(|s| Beyond::new(s, tile.loaded, 2.0 * tile.margin));
        let region = Region {
            loaded: tile.loaded,
            beyond: beyond.as_ref(),
        };
        let mut sel =
            select(&tile.points, &tile.ids, self.hole, region).map_err(KernelError::failed)?;
        if sel.doubtful[..tile.n_core].iter().any(|&d| d) {
            // Doubt starts at the loaded region's faces and reaches `depth`
            // in: a margin beyond that depth (with room to spare, as the
            // reach varies along the faces) leaves the core clear.
            let depth = doubt_depth(tile, &sel.doubtful);
            KernelError::unless_short(DEPTH_SPARE * depth - tile.margin, tile.margin)?;
        }
        let owner_is_core = |t: &[u32; 3]| {
            let first = t.iter().min_by_key(|&&v| tile.ids[v as usize]);
            first.is_some_and(|&v| (v as usize) < tile.n_core)
        };
        // The owned triangles stay in place: one copy, of the others.
        let mut owned = std::mem::take(&mut sel.tris);
        let beside: Vec<[u32; 3]> = owned
            .iter()
            .filter(|t| !owner_is_core(t))
            .copied()
            .collect();
        owned.retain(owner_is_core);
        if owned.iter().any(|t| doubtful_edge(t, &sel.doubtful)) {
            // Doubt within a triangle of the core: the order of that edge
            // is not proven, so neither are the seams and winding through it.
            let depth = doubt_depth(tile, &sel.doubtful);
            let short = (DEPTH_SPARE * depth - tile.margin).max(f64::MIN_POSITIVE);
            KernelError::unless_short(short, tile.margin)?;
        }
        let w = wind_beside(&mut owned, &beside);
        let seams = seam_edges(&owned, &beside, &w.component, tile);
        let mut volumes = vec![0.0; w.inconsistent.len()];
        for (t, &c) in owned.iter().zip(&w.component) {
            volumes[c as usize] += volume6(&tile.points, *t, DVec3::ZERO);
        }
        Ok(DelaunayTile {
            tris: owned
                .iter()
                .map(|t| t.map(|v| tile.store_index(v as usize)))
                .collect(),
            component: w.component,
            inconsistent: w.inconsistent,
            volumes,
            seams,
            report: sel.report,
        })
    }
}

/// Margin asked for per depth of doubt seen (see `run`).
const DEPTH_SPARE: f64 = 1.25;

/// How far inside the loaded region the deepest doubtful point lies.
fn doubt_depth(tile: &TilePoints, doubtful: &[bool]) -> f64 {
    tile.points
        .iter()
        .zip(doubtful)
        .filter(|(_, &d)| d)
        .map(|(p, _)| tile.room(*p))
        .fold(0.0, f64::max)
}

/// Whether some edge of `t` joins two doubtful corners.
fn doubtful_edge(t: &[u32; 3], doubtful: &[bool]) -> bool {
    (0..3).any(|k| doubtful[t[k] as usize] && doubtful[t[(k + 1) % 3] as usize])
}

/// Edges of owned triangles that exactly one other triangle shares, not
/// owned (`beside`): the edges the tile that owns it winds across to this
/// one. Read off the owned triangles and the edges' order in the cloud:
/// matching by the tile's other triangles' edges missed joins (the 10M
/// noisy dragon was reported as 9 components in 256 tiles and 11 in 4,
/// and a missed join leaves two sides wound apart), and pairing edges of
/// order one among the owned paired two triangles of a non-manifold edge
/// whose third lay in another tile, which the untiled walk never crosses.
/// Boundary and non-manifold edges are not sent: they join nothing.
fn seam_edges(
    owned: &[[u32; 3]],
    beside: &[[u32; 3]],
    component: &[u32],
    tile: &TilePoints,
) -> Vec<(u64, u64, u32)> {
    let key = |a: u32, b: u32| (a.min(b), a.max(b));
    let sides = |t: &[u32; 3]| [key(t[0], t[1]), key(t[1], t[2]), key(t[0], t[2])];
    let mut mine: Vec<(u32, u32)> = owned.iter().flat_map(sides).collect();
    mine.sort_unstable();
    let mut all: Vec<(u32, u32)> = beside
        .iter()
        .flat_map(sides)
        .filter(|e| mine.binary_search(e).is_ok())
        .chain(mine.iter().copied())
        .collect();
    all.sort_unstable();
    let order = |edges: &[(u32, u32)], e: (u32, u32)| {
        edges.partition_point(|&x| x <= e) - edges.partition_point(|&x| x < e)
    };
    let mut out = Vec::new();
    for (t, c) in owned.iter().zip(component) {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            if order(&mine, key(a, b)) == 1 && order(&all, key(a, b)) == 2 {
                out.push((
                    tile.store_index(a as usize),
                    tile.store_index(b as usize),
                    *c,
                ));
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;
    use glam::DVec3;
    use std::collections::HashMap;

    /// Seam edges are exactly the owned triangles' edges that one owned
    /// and one other triangle share, each as its triangle runs it, with
    /// its component: checked against counting every edge, over random
    /// triangle sets with shared, lone and non-manifold edges.
    #[test]
    fn seam_edges_are_the_edges_an_owned_and_one_other_triangle_share() {
        let tile = TilePoints::whole(vec![DVec3::ZERO; 12]);
        let mut rng = Rng::new(7);
        let mut random = |n: usize| {
            let mut tris: Vec<[u32; 3]> = Vec::new();
            while tris.len() < n {
                let t = [0, 1, 2].map(|_| rng.below(12) as u32);
                if t[0] != t[1] && t[1] != t[2] && t[0] != t[2] {
                    tris.push(t);
                }
            }
            tris
        };
        let (mut seen, mut kept) = (0, 0);
        for _ in 0..200 {
            let (owned, beside) = (random(8), random(8));
            let component: Vec<u32> = (0..owned.len() as u32).map(|t| t % 3).collect();
            let mut order: HashMap<(u32, u32), (usize, usize)> = HashMap::new();
            for (t, mine) in owned
                .iter()
                .map(|t| (t, 1))
                .chain(beside.iter().map(|t| (t, 0)))
            {
                for k in 0..3 {
                    let (a, b) = (t[k], t[(k + 1) % 3]);
                    let o = order.entry((a.min(b), a.max(b))).or_default();
                    o.0 += mine;
                    o.1 += 1;
                }
            }
            let mut want = Vec::new();
            for (t, c) in owned.iter().zip(&component) {
                for k in 0..3 {
                    let (a, b) = (t[k], t[(k + 1) % 3]);
                    seen += 1;
                    if order[&(a.min(b), a.max(b))] == (1, 2) {
                        want.push((a as u64, b as u64, *c));
                    }
                }
            }
            kept += want.len();
            assert_eq!(seam_edges(&owned, &beside, &component, &tile), want);
        }
        // The sets exercise both outcomes.
        assert!(kept > 0 && kept < seen, "{kept} of {seen}");
    }
}
