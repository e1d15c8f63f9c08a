//! When a seam vertex is complete: the tiles owning the four cubes around
//! a vertex's lattice edge, found among the tiles whose cores touch the
//! arriving tile's, and the last of them in tile order. Once that tile has
//! been stitched no triangle can name the vertex again, so the stitcher
//! forgets its key and the hole finder its settled edges. Without this the
//! seam state grew with the whole run: 56k keys and 64k edges on the 10M
//! dragon (64 tiles), about 4 million of each at a billion points, some
//! 220 MiB in hash tables beside the tiles.

use super::blocks::BLOCK;
use super::cubes::owns;
use super::lattice::{edge_from_key, Lattice};
use crate::geom::Aabb;

/// Tile index standing for "never complete" (an owner not found, which
/// the tiles' partition of space rules out; kept for safety).
pub const NEVER: u32 = u32::MAX;

/// Every tile's core box, in tile (stitching) order.
pub struct TileOwners {
    cores: Vec<Aabb>,
}

/// The tiles that may own a cube next to one tile's cubes.
pub struct Neighbourhood {
    tile: u32,
    tiles: Vec<u32>,
}

impl TileOwners {
    pub fn new(cores: Vec<Aabb>) -> Self {
        TileOwners { cores }
    }

    /// Tiles whose cores come within two blocks and a cube (and a little)
    /// of `tile`'s: an owned cube lies within a block past the core, the
    /// cubes around its edges within one cube of it, and their owners'
    /// cores within a block of those.
    pub fn around(&self, tile: usize, cell: f64) -> Neighbourhood {
        let Some(core) = self.cores.get(tile) else {
            return Neighbourhood {
                tile: tile as u32,
                tiles: Vec::new(),
            };
        };
        let reach = (2 * BLOCK + 1) as f64 * 1.01 * cell;
        let near = |other: &Aabb| {
            (0..3)
                .all(|a| other.min[a] <= core.max[a] + reach && core.min[a] - reach <= other.max[a])
        };
        Neighbourhood {
            tile: tile as u32,
            tiles: (0..self.cores.len() as u32)
                .filter(|&u| near(&self.cores[u as usize]))
                .collect(),
        }
    }

    /// The last tile (in stitching order) owning one of the four cubes
    /// around lattice edge `key`; [`NEVER`] if one has no owner in sight.
    pub fn last_owner(&self, lattice: &Lattice, around: &Neighbourhood, key: u64) -> u32 {
        let Ok((cell, axis)) = edge_from_key(key) else {
            return NEVER;
        };
        let (b, c) = match axis {
            0 => (1, 2),
            1 => (0, 2),
            _ => (0, 1),
        };
        let mut last = around.tile;
        for (db, dc) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
            let mut cube = cell;
            cube[b] -= db;
            cube[c] -= dc;
            let owner = around
                .tiles
                .iter()
                .find(|&&u| owns(lattice, &self.cores[u as usize], cube));
            match owner {
                Some(&u) => last = last.max(u),
                None => return NEVER,
            }
        }
        last
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    /// Four tiles splitting space at x = 0 and y = 0 (cores are half-open,
    /// outer faces at infinity); a z-edge at the origin has one cube in
    /// each, a z-edge inside the first has all four there.
    #[test]
    fn the_last_owner_of_an_edge_on_a_corner_of_four_tiles() {
        let inf = f64::INFINITY;
        let b = |x0: f64, x1: f64, y0: f64, y1: f64| Aabb {
            min: DVec3::new(x0, y0, -inf),
            max: DVec3::new(x1, y1, inf),
        };
        let owners = TileOwners::new(vec![
            b(-inf, 0.0, -inf, 0.0),
            b(0.0, inf, -inf, 0.0),
            b(-inf, 0.0, 0.0, inf),
            b(0.0, inf, 0.0, inf),
        ]);
        let lattice = Lattice::new(DVec3::ZERO, 1.0).unwrap();
        let key = |c: [i64; 3]| super::super::lattice::edge_key(c, 2).unwrap();
        for t in 0..4 {
            let around = owners.around(t, 1.0);
            assert_eq!(around.tiles, vec![0, 1, 2, 3]);
            assert_eq!(owners.last_owner(&lattice, &around, key([0, 0, 5])), 3);
        }
        let around = owners.around(0, 1.0);
        assert_eq!(owners.last_owner(&lattice, &around, key([-3, -3, 5])), 0);
        // An edge on the x = 0 face below y = 0: tiles 0 and 1.
        assert_eq!(owners.last_owner(&lattice, &around, key([0, -3, 5])), 1);
    }
}
