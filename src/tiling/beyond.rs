//! The points a tile did not load, asked about one ball at a time: whether
//! any stored point outside a tile's loaded region lies inside a ball.
//!
//! A kernel whose proofs are "this sphere holds no point of the cloud"
//! (the Delaunay surface's empty spheres) can prove a sphere that pokes out
//! of its loaded region without loading a wider margin: it asks the store.
//! Only the blocks whose bounds meet the ball are read, so a ball costs a
//! few blocks; the block bounds of a store tile are read once, on first
//! use, and only for tiles some ball reached (a tile's neighbours).

use super::load::entry_bounds;
use crate::geom::Aabb;
use crate::store::{PointStore, BLOCK};
use glam::DVec3;
use std::sync::OnceLock;

/// The store seen from one tile: every point outside `loaded`, up to
/// `reach` beyond it.
pub struct Beyond<'a> {
    store: &'a PointStore,
    loaded: Aabb,
    /// `loaded` grown by the reach: no ball may leave it, so the points
    /// read (and kept) are a shell around the tile's, never the store.
    within: Aabb,
    /// Per store tile: its blocks, read on first use (`None` when the read
    /// failed: every ball meeting the tile is then unproven).
    tiles: Vec<OnceLock<Option<Blocks>>>,
}

/// One store tile's blocks: their bounds, and the points of each block
/// outside the loaded region, read when a ball first meets the block.
struct Blocks {
    bounds: Vec<Aabb>,
    points: Vec<OnceLock<Option<Vec<DVec3>>>>,
}

impl<'a> Beyond<'a> {
    /// The points outside `loaded` up to `reach` beyond it: those read are
    /// kept (24 B each, against a kernel's hundreds per loaded point) and
    /// stay within a shell round the tile.
    pub fn new(store: &'a PointStore, loaded: Aabb, reach: f64) -> Self {
        Beyond {
            store,
            loaded,
            within: loaded.expanded(reach),
            tiles: store.tiles().iter().map(|_| OnceLock::new()).collect(),
        }
    }

    /// Whether no stored point outside the loaded region lies within
    /// `radius` of `centre` (closed ball). A ball reaching too far, or a
    /// store read that fails, answers "not known empty", which costs the
    /// caller a proof, never a wrong one.
    pub fn ball_is_empty(&self, centre: DVec3, radius: f64) -> bool {
        self.each_outside(centre, radius, |_| false) == Seen::All
    }

    /// Calls `visit` on every stored point outside the loaded region within
    /// `radius` of `centre` (closed ball), until it returns false.
    pub fn each_outside(
        &self,
        centre: DVec3,
        radius: f64,
        mut visit: impl FnMut(DVec3) -> bool,
    ) -> Seen {
        let reach = Aabb::new(centre - DVec3::splat(radius), centre + DVec3::splat(radius));
        if !(self.within.contains(reach.min) && self.within.contains(reach.max)) {
            return Seen::Unknown;
        }
        let r2 = radius * radius;
        for (t, entry) in self.store.tiles().iter().enumerate() {
            if entry.count == 0 || !entry_bounds(entry).intersects(&reach) {
                continue;
            }
            let Some(blocks) = self.blocks_of(t) else {
                return Seen::Unknown;
            };
            for (b, bounds) in blocks.bounds.iter().enumerate() {
                if !bounds.intersects(&reach) || box_dist2(bounds, centre) > r2 {
                    continue;
                }
                let Some(pts) = self.outside(t, &blocks.points[b], b) else {
                    return Seen::Unknown;
                };
                let mut near = pts.iter().filter(|p| p.distance_squared(centre) <= r2);
                if !near.all(|p| visit(*p)) {
                    return Seen::Stopped;
                }
            }
        }
        Seen::All
    }

    fn blocks_of(&self, t: usize) -> Option<&Blocks> {
        self.tiles[t]
            .get_or_init(|| {
                let entry = &self.store.tiles()[t];
                let mut bounds = Vec::new();
                let n = entry.count.div_ceil(BLOCK);
                self.store
                    .read_blocks(entry.first_block, n, &mut bounds)
                    .ok()?;
                let points = bounds.iter().map(|_| OnceLock::new()).collect();
                Some(Blocks { bounds, points })
            })
            .as_ref()
    }

    /// The points of block `b` of store tile `t` outside the loaded region.
    fn outside<'s>(
        &self,
        t: usize,
        cache: &'s OnceLock<Option<Vec<DVec3>>>,
        b: usize,
    ) -> Option<&'s [DVec3]> {
        cache
            .get_or_init(|| {
                let entry = &self.store.tiles()[t];
                let first = entry.start + b as u64 * BLOCK;
                let count = BLOCK.min(entry.start + entry.count - first);
                let mut pts = Vec::new();
                self.store.read_points(first, count, &mut pts).ok()?;
                pts.retain(|p| !self.loaded.contains(*p));
                Some(pts)
            })
            .as_deref()
    }
}

/// How a visit of the points in a ball ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Seen {
    /// Every point was visited.
    All,
    /// The visitor stopped at a point.
    Stopped,
    /// The ball reaches farther than the tile may read, or a store read
    /// failed: what it holds is not known (a proof built on the visits then
    /// fails, never lies).
    Unknown,
}

/// Squared distance from `p` to the box (0 inside).
fn box_dist2(b: &Aabb, p: DVec3) -> f64 {
    let d = (b.min - p).max(p - b.max).max(DVec3::ZERO);
    d.length_squared()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    /// A wavy sheet in a store of several tiles, and the points as stored
    /// (f32 relative to the origin, as `Beyond` reads them).
    fn sheet_store(dir: &std::path::Path) -> (PointStore, Vec<DVec3>) {
        let mut rng = Rng::new(7);
        let pts: Vec<DVec3> = (0..20_000)
            .map(|_| {
                let (x, y) = (rng.range(0.0, 10.0), rng.range(0.0, 10.0));
                DVec3::new(x, y, (x * 1.3).sin() * 0.5)
            })
            .collect();
        let store = crate::store::test_store::store_of(pts, 3000, dir);
        let mut stored = Vec::new();
        let mut part = Vec::new();
        for t in store.tiles() {
            store.read_points(t.start, t.count, &mut part).unwrap();
            stored.extend_from_slice(&part);
        }
        (store, stored)
    }

    #[test]
    fn balls_against_brute_force() {
        let dir = tempfile::tempdir().unwrap();
        let (store, stored) = sheet_store(&dir.path().join("s"));
        assert!(store.tiles().len() > 4);
        // The box and balls in the store's coordinates (relative to its
        // origin), balls round stored points so that many meet some.
        let o = store.origin();
        let loaded = Aabb::new(
            DVec3::new(2.0, 3.0, -1.0) - o,
            DVec3::new(6.0, 7.0, 1.0) - o,
        );
        let beyond = Beyond::new(&store, loaded, 2.5);
        let mut rng = Rng::new(11);
        let (mut empty, mut full, mut far) = (0, 0, 0);
        for _ in 0..400 {
            let near = stored[rng.below(stored.len() as u64) as usize];
            let c = near + rng.gaussian_vector(0.2);
            let r = rng.range(0.0, 0.3);
            let too_far = !beyond.within.contains(c - r) || !beyond.within.contains(c + r);
            if too_far {
                assert!(!beyond.ball_is_empty(c, r), "ball {c} {r} reaches too far");
                far += 1;
                continue;
            }
            let truth = !stored
                .iter()
                .any(|p| !loaded.contains(*p) && p.distance_squared(c) <= r * r);
            assert_eq!(beyond.ball_is_empty(c, r), truth, "ball {c} {r}");
            if truth {
                empty += 1;
            } else {
                full += 1;
            }
        }
        // Every answer was exercised.
        assert!(
            empty > 50 && full > 50 && far > 10,
            "{empty} empty, {full} not, {far} too far"
        );
    }

    #[test]
    fn distance_to_a_box() {
        let b = Aabb::new(DVec3::ZERO, DVec3::ONE);
        assert_eq!(box_dist2(&b, DVec3::splat(0.5)), 0.0);
        assert_eq!(box_dist2(&b, DVec3::new(2.0, 0.5, 0.5)), 1.0);
        assert_eq!(box_dist2(&b, DVec3::new(-1.0, 2.0, 0.5)), 2.0);
    }
}
