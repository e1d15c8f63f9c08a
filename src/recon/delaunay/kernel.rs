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
//! Winding is global (a component may cross many tiles, and a twist is
//! found only over the whole surface), so it is the seam side's
//! (`mesh::untwist`): the kernel gives each owned triangle its unit normal
//! with its corners in input order and its signed volume as its corners
//! are listed, both computed from the corners in input order so that
//! every tiling gives the same bits. An
//! edge's order is the cloud's: every triangle on it has one of its
//! corners, and a triangle with a sure corner is the cloud's (a tile whose
//! owned triangle has an edge between two doubtful corners asks for a
//! wider margin).

use super::fan::Hole;
use super::select::{select, SelectionReport};
use super::umbrella::Region;
use crate::mesh::untwist::pack_normal;
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
    /// Owned triangles, as store indices, in no particular winding.
    pub tris: Vec<[u64; 3]>,
    /// Each triangle's unit normal with its corners in input order
    /// (`mesh::untwist::pack_normal`).
    pub normals: Vec<u32>,
    /// Six times each triangle's signed volume about the store origin, as
    /// its corners run.
    pub volumes: Vec<f64>,
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

    fn name(&self) -> &'static str {
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
        let mut owned = std::mem::take(&mut sel.tris);
        if owned
            .iter()
            .any(|t| owner_is_core(t) && doubtful_edge(t, &sel.doubtful))
        {
            // Doubt within a triangle of the core: the order of that edge
            // is not proven, so neither is the winding through it.
            let depth = doubt_depth(tile, &sel.doubtful);
            let short = (DEPTH_SPARE * depth - tile.margin).max(f64::MIN_POSITIVE);
            KernelError::unless_short(short, tile.margin)?;
        }
        owned.retain(owner_is_core);
        let tris: Vec<[u64; 3]> = owned
            .iter()
            .map(|t| t.map(|v| tile.store_index(v as usize)))
            .collect();
        let (normals, volumes) = owned
            .iter()
            .map(|t| facing(&tile.points, *t, t.map(|v| tile.ids[v as usize])))
            .unzip();
        Ok(DelaunayTile {
            tris,
            normals,
            volumes,
            report: sel.report,
        })
    }
}

/// Triangle `t`'s packed unit normal with its corners in input order
/// (`ids`, the points' input-order ids), and six times its signed volume
/// about the origin computed so and turned as `t` lists them: the same
/// bits in every tiling, whatever order a tile lists the corners in.
fn facing(points: &[DVec3], t: [u32; 3], ids: [u64; 3]) -> (u32, f64) {
    let mut order = [0usize, 1, 2];
    order.sort_unstable_by_key(|&k| ids[k]);
    // A rotation of the corners keeps the winding; a swap turns it.
    let turned = !matches!(order, [0, 1, 2] | [1, 2, 0] | [2, 0, 1]);
    let [a, b, c] = order.map(|k| points[t[k] as usize]);
    let normal = (b - a).cross(c - a).normalize_or_zero();
    let volume6 = a.dot(b.cross(c));
    (pack_normal(normal), if turned { -volume6 } else { volume6 })
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    /// Any listing of a triangle's corners gives the same normal (the
    /// store order's) and the same volume, turned over when the listing
    /// is not a rotation of the store order.
    #[test]
    fn facing_depends_on_the_winding_not_the_listing() {
        let mut rng = Rng::new(3);
        for _ in 0..500 {
            let points: Vec<DVec3> = (0..3)
                .map(|_| DVec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 1e3)
                .collect();
            let ids = [
                rng.below(1000),
                1000 + rng.below(1000),
                2000 + rng.below(1000),
            ];
            let (n0, v0) = facing(&points, [0, 1, 2], ids);
            let plain = (points[1] - points[0]).cross(points[2] - points[0]);
            let back = crate::mesh::untwist::tests::unpack(n0);
            assert!(back.dot(plain.normalize()) > 0.9999);
            for (perm, turned) in [
                ([1, 2, 0], false),
                ([2, 0, 1], false),
                ([1, 0, 2], true),
                ([0, 2, 1], true),
                ([2, 1, 0], true),
            ] {
                let (n, v) = facing(&points, perm, perm.map(|k| ids[k as usize]));
                assert_eq!(n, n0);
                assert_eq!(v, if turned { -v0 } else { v0 });
            }
        }
    }
}
