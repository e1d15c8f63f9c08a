//! The pairs the sign travels along, as spanning-forest edges, and their
//! cost: the one definition the in-memory propagation and the tile kernel
//! share, so both see bit-identical edges.
//!
//! A pair in the neighbourhood (within `r`, or among the k nearest) with
//! `w >= tau` is a propagation pair (paper 5 step 2), cost `1 - w` in
//! `[0, 1 - tau]`, so the strongest pair is the cheapest. Any other pair
//! (`w < tau`, or a bridge to one of the k nearest beyond `r`) serves only
//! the nearest-distance rule: cost `2 + distance`, above every propagation
//! pair and ordered by distance. Costs are computed with the two points in
//! id order, so a pair costs the same whichever end asks.

use super::SourceParams;
use crate::normals::forest::Edge;
use crate::normals::EdgeCost;
use glam::DVec3;

/// One end of a pair: input id, union-find slot (see
/// [`crate::normals::forest::Edge`]), position, unit normal.
#[derive(Clone, Copy, Debug)]
pub struct End {
    pub id: u32,
    pub slot: u32,
    pub p: DVec3,
    pub n: DVec3,
}

/// How pairs are weighed.
#[derive(Clone, Copy, Debug)]
pub struct PairRule {
    pub tau: f64,
    pub weight: EdgeCost,
    /// `r^2` for radius neighbourhoods: a pair farther than `r` is a bridge.
    /// `None` for k-nearest neighbourhoods: every pair asked is in it.
    pub radius2: Option<f64>,
}

impl PairRule {
    pub fn new(params: &SourceParams) -> Self {
        PairRule {
            tau: params.tau,
            weight: params.weight,
            radius2: match params.hood {
                super::Neighbourhood::Radius(r) => Some(r * r),
                super::Neighbourhood::Nearest(_) => None,
            },
        }
    }

    /// The pair as an edge: cost as above, sign of `n_a . n_b` (negative:
    /// one of the two flips).
    pub fn edge(&self, a: End, b: End) -> Edge {
        let (x, y) = if a.id <= b.id { (a, b) } else { (b, a) };
        let d = y.p - x.p;
        let d2 = d.length_squared();
        let dot = x.n.dot(y.n);
        let in_hood = self.radius2.is_none_or(|r2| d2 <= r2);
        let w = self.strength(d, d2.sqrt(), x.n, y.n, dot);
        let cost = if in_hood && w >= self.tau {
            1.0 - w
        } else {
            2.0 + d2.sqrt()
        };
        Edge::between([x.id, x.slot], [y.id, y.slot], cost, dot)
    }

    /// The paper's `w = |n_x . n_y|`, or with [`EdgeCost::TangentOffset`]
    /// that minus the pair's mean tangent-plane offset
    /// `(|d . n_x| + |d . n_y|) / 2|d|`: a pair across a part thinner than
    /// `r` has antiparallel normals (`w` near 1) but runs along them.
    fn strength(&self, d: DVec3, len: f64, nx: DVec3, ny: DVec3, dot: f64) -> f64 {
        let w = dot.abs();
        match self.weight {
            EdgeCost::Paper => w,
            EdgeCost::TangentOffset if len > 0.0 => {
                w - (d.dot(nx).abs() + d.dot(ny).abs()) / (2.0 * len)
            }
            EdgeCost::TangentOffset => w,
        }
    }
}

/// Whether an edge propagates (rather than only bridging a gap).
pub fn propagates(e: &Edge) -> bool {
    e.w.abs() < 2.0
}

#[cfg(test)]
mod tests {
    use super::*;

    fn end(id: u32, p: [f64; 3], n: [f64; 3]) -> End {
        End {
            id,
            slot: id,
            p: DVec3::from_array(p),
            n: DVec3::from_array(n).normalize(),
        }
    }

    #[test]
    fn cost_is_symmetric_and_tiered() {
        let rule = PairRule {
            tau: 0.6,
            weight: EdgeCost::TangentOffset,
            radius2: Some(1.0),
        };
        let a = end(4, [0.0, 0.0, 0.0], [0.0, 0.1, 1.0]);
        let b = end(9, [0.5, 0.1, 0.02], [0.05, 0.0, -1.0]);
        let (e, f) = (rule.edge(a, b), rule.edge(b, a));
        assert_eq!(e.to_bytes(), f.to_bytes());
        assert!(propagates(&e) && e.flips());
        // Beyond r: a bridge costing 2 + distance.
        let c = end(1, [3.0, 0.0, 0.0], [0.0, 0.0, 1.0]);
        let g = rule.edge(a, c);
        assert!(!propagates(&g) && (g.w - 5.0).abs() < 1e-12);
        // Perpendicular normals: w < tau, a bridge too.
        let d = end(2, [0.3, 0.0, 0.0], [1.0, 0.0, 0.0]);
        assert!(!propagates(&rule.edge(a, d)));
    }

    #[test]
    fn offset_demotes_pairs_across_a_thin_part() {
        let rule = |weight| PairRule {
            tau: 0.6,
            weight,
            radius2: Some(1.0),
        };
        let top = end(1, [0.0, 0.0, 0.05], [0.0, 0.0, 1.0]);
        let bottom = end(2, [0.0, 0.0, -0.05], [0.0, 0.0, -1.0]);
        assert!(propagates(&rule(EdgeCost::Paper).edge(top, bottom)));
        assert!(!propagates(
            &rule(EdgeCost::TangentOffset).edge(top, bottom)
        ));
    }
}
