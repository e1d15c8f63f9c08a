//! Anchors: points whose own normal says which way they face, tied to one
//! virtual node (the "sky") before the spanning tree joins anything else.
//!
//! Aerial lidar sees every surface from above, so a normal that is not
//! near horizontal faces up: that is evidence, point by point, the
//! stronger the more level the normal ([`SKY_COST`]). Paper 1 (section 2.4) instead signs a whole component from
//! one root and carries the sign along the tree, and on a town (PDAL's
//! autzen, ground, roofs, trees) the tree passes through trunks and crowns
//! whose normals are noise: 99.97 % of the ground faced down. Deviation:
//! every anchor gets an edge, with the parity that turns it to face the
//! direction, to a virtual node (the sky), costing little for a level
//! normal and more for a steep one ([`SKY_COST`]); Kruskal then runs over
//! the tile forests and these edges together. Level surfaces join the
//! sky before anything else, an edge between two points already tied to
//! it closes a cycle and is dropped, and a steep point (walls, steep
//! slopes, overhangs) takes its sign from whichever is cheaper: its own
//! word, or its cheapest path to a surface tied to the sky: the "repair
//! past vertical".
//!
//! Exact in tiles: the sky's edges are added to each tile's forest for
//! its core's anchors, and the tile keeps the minimum spanning forest of
//! both (the same function as the kernel's).
//! An edge outside a tile's forest is the heaviest of a cycle of the tile's
//! edges, which the global graph holds too, so it is in no global tree
//! with or without the sky's edges (cycle property): the union of the
//! tiles' augmented forests holds the global tree of the graph plus the
//! sky, and the global passes (in memory and external) need nothing but a
//! slot for the sky, one past the last point.

use crate::normals::forest::{spanning_forest, Edge};
use crate::normals::FLAG_DEGENERATE;
use glam::DVec3;
use std::ops::Range;

/// Input id of the sky: above every point's id (ids are below
/// `store::build::MAX_POINTS`), so its edges sort after a point's other
/// edges of the same cost.
pub(crate) const SKY_ID: u32 = u32::MAX;

/// Least `|n . direction|` of an anchor: more than 2.9 degrees off
/// perpendicular to the direction (a normal nearer horizontal says
/// nothing of up or down).
pub(crate) const ANCHOR_COS: f32 = 0.05;

/// A sky edge costs `SKY_COST * (1 - |n . direction|)`: 0 for a level
/// surface, up to 0.25 for a steep one, where an edge of the tree costs
/// `1 - |n_i . n_j|` plus the tangent-plane offset (0 to 2). So a point
/// takes its own word only when no neighbour offers a cheaper one: the
/// middle of a wall, its normal a few degrees off horizontal by noise,
/// hangs off its wall neighbours, and the wall off its most level edge
/// (at a wall's foot or eaves the neighbourhood mixes ground or roof in
/// and the true normal leans up, outward); a ground point whose k nearest
/// reach into vegetation (its normal steep, its neighbours' normals
/// noise) takes its own. Measured, ground facing up at (least `|n.z|`,
/// scale): lidR's Megaplot (sparse ground under canopy: 555 of 7,389
/// ground normals more than 60 degrees off vertical) 96.85 % at (0.5, 0),
/// 99.20 % at (0.1, 0), 99.16 % at (0.05, 0.25), 98.16 % at (0.05, 0.5);
/// the test terrain's cliffs (`scangen terrain`, taken as aerial),
/// normals agreeing with the true surface: 99.9945 %, 99.7460 %,
/// 99.9570 %, 99.9930 %; PDAL's sample_c walls faced their lower side
/// (outward) at 98.18 % in all four.
pub(crate) const SKY_COST: f64 = 0.25;

/// The sky of a store: the direction every anchor must face and the
/// union-find slot the global passes give the sky.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Anchoring {
    direction: [f32; 3],
    sky_slot: u32,
    /// Least `|n . direction|` of an anchor.
    floor: f32,
    /// A sky edge costs `scale * (1 - |n . direction|)`.
    scale: f64,
}

impl Anchoring {
    /// The sky facing `direction` (normalised; `None` when it is zero or
    /// not finite) of a store of `points` points.
    pub(crate) fn new(direction: DVec3, points: u64) -> Option<Self> {
        let d = direction.try_normalize()?;
        Some(Anchoring {
            direction: d.as_vec3().to_array(),
            sky_slot: u32::try_from(points).ok()?,
            floor: ANCHOR_COS,
            scale: SKY_COST,
        })
    }

    /// The same with its own floor (least `|n . direction|`, in `[0, 1]`)
    /// and sky edge cost scale (`>= 0`).
    pub(crate) fn with(mut self, floor: f32, scale: f64) -> Self {
        self.floor = floor;
        self.scale = scale.max(0.0);
        self
    }

    /// Whether a normal `n` anchors its point, and if so whether it must
    /// flip to face the direction and what its sky edge costs.
    pub(crate) fn anchors(&self, n: [f32; 3]) -> Option<(bool, f64)> {
        let d = self.direction;
        let dot = n[0] * d[0] + n[1] * d[1] + n[2] * d[2];
        let (floor, scale) = (self.floor, self.scale);
        (dot.abs() >= floor).then_some((dot < 0.0, scale * (1.0 - f64::from(dot.abs()))))
    }

    /// The minimum spanning forest of a tile's `forest` (sorted by key,
    /// slots are store indices) and the sky's edges to the anchors of its
    /// core (store range `core`; `ids`, `normals` (3 a point) and `flags`
    /// of the core in store order). Sorted by key, as the runs want.
    pub(crate) fn forest(
        &self,
        forest: Vec<Edge>,
        core: Range<u64>,
        ids: &[u64],
        normals: &[f32],
        flags: &[u8],
    ) -> Vec<Edge> {
        let mut edges = forest;
        for (k, &id) in ids.iter().enumerate() {
            if flags.get(k).is_none_or(|f| f & FLAG_DEGENERATE != 0) {
                continue;
            }
            let Some(n) = normals.get(3 * k..3 * k + 3) else {
                continue;
            };
            if let Some((flip, cost)) = self.anchors([n[0], n[1], n[2]]) {
                let slot = (core.start + k as u64) as u32;
                let dot = if flip { -1.0 } else { 1.0 };
                edges.push(Edge::between(
                    [id as u32, slot],
                    [SKY_ID, self.sky_slot],
                    cost,
                    dot,
                ));
            }
        }
        // Local numbers: core points by their place in the core, the
        // other ends (margin points, the sky) after them, in slot order.
        let count = (core.end - core.start) as u32;
        let mut foreign: Vec<u32> = edges
            .iter()
            .flat_map(|e| e.slots)
            .filter(|&s| !core.contains(&u64::from(s)))
            .collect();
        foreign.sort_unstable();
        foreign.dedup();
        let local = |s: u32| match core.contains(&u64::from(s)) {
            true => (u64::from(s) - core.start) as u32,
            false => count + foreign.binary_search(&s).unwrap_or(0) as u32,
        };
        for e in &mut edges {
            e.slots = e.slots.map(local);
        }
        let n = count as usize + foreign.len();
        let mut out = spanning_forest(edges, n);
        let global = |l: u32| match l < count {
            true => (core.start + u64::from(l)) as u32,
            false => foreign[(l - count) as usize],
        };
        for e in &mut out {
            e.slots = e.slots.map(global);
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::normals::unionfind::ParityUnionFind;

    #[test]
    fn anchors_face_the_direction_and_steep_points_are_left_to_the_tree() {
        let a = Anchoring::new(DVec3::new(0.0, 0.0, 2.0), 10).unwrap();
        let cost = |nz: f64| SKY_COST * (1.0 - nz);
        assert_eq!(a.anchors([0.0, 0.0, 1.0]), Some((false, 0.0)));
        let (flip, c) = a.anchors([0.0, 0.6, -0.8]).unwrap();
        assert!(flip && (c - cost(0.8)).abs() < 1e-6);
        assert_eq!(a.anchors([1.0, 0.0, 0.0]), None);
        assert_eq!(a.anchors([0.0, 0.9995, 0.03]), None);
        let (flip, c) = a.anchors([0.0, 0.9, 0.4]).unwrap();
        assert!(!flip && (c - cost(0.4)).abs() < 1e-6);
        // A single source's anchors: within 45 degrees, at no cost.
        let s = a.with(0.7, 0.0);
        assert_eq!(s.anchors([0.0, 0.6, -0.8]), Some((true, 0.0)));
        assert_eq!(s.anchors([0.0, 0.9, 0.4]), None);
        assert!(Anchoring::new(DVec3::ZERO, 10).is_none());
    }

    /// A roof (up), a wall (sideways) and ground whose tree path runs
    /// through the wall: every level point faces up whatever the tree's
    /// parities, and the wall takes its sign from its cheapest anchor.
    #[test]
    fn the_sky_ties_every_anchor_and_the_tree_signs_the_rest() {
        // Points 0..3: slots 10..13; 0 roof facing down (PCA sign), 1 wall,
        // 2 ground facing up, 3 ground facing down.
        let normals = [
            0.0, 0.0, -1.0, //
            1.0, 0.0, 0.0, //
            0.0, 0.0, 1.0, //
            0.1, 0.0, -0.99,
        ];
        let flags = [0u8; 4];
        let ids = [5u64, 6, 7, 8];
        // Tree: roof-wall (dot 0.1, no flip), wall-ground (dot -0.1, flips),
        // ground-ground (dot -0.99, flips).
        let forest = vec![
            Edge::between([7, 12], [8, 13], 0.01, -0.99),
            Edge::between([5, 10], [6, 11], 0.9, 0.1),
            Edge::between([6, 11], [7, 12], 0.9, -0.1),
        ];
        let mut forest = forest;
        forest.sort_by_key(|e| e.key());
        let a = Anchoring::new(DVec3::Z, 14).unwrap();
        let out = a.forest(forest, 10..14, &ids, &normals, &flags);
        assert!(out.windows(2).all(|w| w[0].key() <= w[1].key()));
        // Three anchors to the sky, one edge to the wall.
        assert_eq!(out.len(), 4);
        let mut uf = ParityUnionFind::new(15);
        for e in &out {
            uf.union(e.slots[0], e.slots[1], e.flips());
        }
        let (sky_root, sky_parity) = uf.find(14);
        let mut flip = |s: u32| {
            let (r, p) = uf.find(s);
            assert_eq!(r, sky_root);
            p ^ sky_parity
        };
        assert!(flip(10), "the roof faced down: flipped");
        assert!(!flip(12));
        assert!(flip(13));
        // The wall hangs off the roof (edge cost 0.9 either way; the
        // roof's edge comes first by ids): no flip relative to the roof,
        // which flips.
        assert!(flip(11));
    }
}
