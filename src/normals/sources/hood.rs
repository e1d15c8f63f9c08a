//! Neighbourhoods for the six-source propagation (paper 5 step 1): every
//! point within radius `r` (exact, through a uniform grid of cell `r`), or
//! the `k` nearest (the paper's choice for curvature-adaptive sampling,
//! through the project's exact kNN index).
//!
//! Both answer in the project's one neighbour order, (squared distance, input
//! id), with distances computed by the one formula, so a tile and the whole
//! cloud see the same neighbourhood for a point whose neighbourhood is loaded.

use super::SourcesError;
use crate::spatial::brute::dist2;
use crate::spatial::{
    build_index, key_runs, neighbour_order, IndexError, KnnBackend, KnnIndex, Neighbour,
};
use glam::DVec3;
use std::collections::HashMap;

/// Which points count as a point's neighbours.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Neighbourhood {
    /// Every point within this distance (paper: 2..4 times the mean spacing).
    Radius(f64),
    /// The k nearest points.
    Nearest(usize),
}

/// A built neighbourhood structure over one cloud.
pub(crate) enum Hoods<'a> {
    Radius(RadiusGrid<'a>),
    Nearest {
        index: Box<dyn KnnIndex + 'a>,
        points: &'a [DVec3],
        k: usize,
    },
}

impl<'a> Hoods<'a> {
    pub(crate) fn build(
        hood: Neighbourhood,
        points: &'a [DVec3],
        ids: &'a [u64],
    ) -> Result<Self, SourcesError> {
        Ok(match hood {
            Neighbourhood::Radius(r) => Hoods::Radius(RadiusGrid::new(points, ids, r)?),
            Neighbourhood::Nearest(k) => {
                if k == 0 {
                    return Err(SourcesError::BadNeighbourhood { hood });
                }
                Hoods::Nearest {
                    index: build_index(KnnBackend::KdTree, points, ids)?,
                    points,
                    k,
                }
            }
        })
    }

    /// The neighbours of point `i` (itself excluded), sorted.
    pub(crate) fn of(&self, i: usize, out: &mut Vec<Neighbour>) {
        match self {
            Hoods::Radius(g) => g.within(i, out),
            Hoods::Nearest { index, points, k } => index.knn(points[i], *k, Some(i as u32), out),
        }
    }
}

/// Exact fixed-radius search: cells of side `r`, so the 27 cells around a
/// point's cell hold every point within `r`. Lookups only, never iteration
/// over the map, so its order cannot leak into results.
pub(crate) struct RadiusGrid<'a> {
    points: &'a [DVec3],
    ids: &'a [u64],
    r2: f64,
    inv: f64,
    /// Point indices sorted by cell; `cells` maps a cell to its range.
    order: Vec<u32>,
    cells: HashMap<[i64; 3], (u32, u32)>,
}

impl<'a> RadiusGrid<'a> {
    pub(crate) fn new(points: &'a [DVec3], ids: &'a [u64], r: f64) -> Result<Self, SourcesError> {
        if !(r.is_finite() && r > 0.0) {
            return Err(SourcesError::BadNeighbourhood {
                hood: Neighbourhood::Radius(r),
            });
        }
        if points.len() != ids.len() {
            return Err(SourcesError::Lengths {
                points: points.len(),
                other: ids.len(),
            });
        }
        if points.len() > u32::MAX as usize {
            let points = points.len();
            return Err(IndexError::TooManyPoints { points }.into());
        }
        let inv = 1.0 / r;
        let mut keyed: Vec<([i64; 3], u32)> = points
            .iter()
            .enumerate()
            .map(|(i, p)| (cell_of(*p, inv), i as u32))
            .collect();
        keyed.sort_unstable();
        let cells: HashMap<_, _> = key_runs(&keyed, |e| e.0).collect();
        Ok(RadiusGrid {
            points,
            ids,
            r2: r * r,
            inv,
            order: keyed.into_iter().map(|(_, i)| i).collect(),
            cells,
        })
    }

    /// Every point within `r` of point `i` (itself excluded), sorted.
    pub(crate) fn within(&self, i: usize, out: &mut Vec<Neighbour>) {
        out.clear();
        let p = self.points[i];
        let c = cell_of(p, self.inv);
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    let key = [
                        c[0].saturating_add(dx),
                        c[1].saturating_add(dy),
                        c[2].saturating_add(dz),
                    ];
                    let Some(&(s, e)) = self.cells.get(&key) else {
                        continue;
                    };
                    for &j in &self.order[s as usize..e as usize] {
                        let d2 = dist2(self.points[j as usize], p);
                        if j as usize != i && d2 <= self.r2 {
                            out.push(Neighbour {
                                dist2: d2,
                                index: j,
                            });
                        }
                    }
                }
            }
        }
        out.sort_unstable_by(|a, b| neighbour_order(self.ids, a, b));
    }
}

fn cell_of(p: DVec3, inv: f64) -> [i64; 3] {
    // `as` saturates, so absurd ratios of extent to radius stay defined.
    [
        (p.x * inv).floor() as i64,
        (p.y * inv).floor() as i64,
        (p.z * inv).floor() as i64,
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    #[test]
    fn radius_grid_matches_brute_force() {
        let seed = 17;
        let mut rng = Rng::new(seed);
        let points: Vec<DVec3> = (0..800)
            .map(|_| DVec3::new(rng.uniform(), rng.uniform(), rng.uniform() * 0.2))
            .collect();
        let ids: Vec<u64> = (0..800u64).map(|i| (i * 7919) % 800).collect();
        let r = 0.07;
        let grid = RadiusGrid::new(&points, &ids, r).unwrap();
        let mut got = Vec::new();
        for i in 0..points.len() {
            grid.within(i, &mut got);
            let mut want: Vec<Neighbour> = (0..points.len())
                .filter(|&j| j != i && dist2(points[j], points[i]) <= r * r)
                .map(|j| Neighbour {
                    dist2: dist2(points[j], points[i]),
                    index: j as u32,
                })
                .collect();
            want.sort_by(|a, b| neighbour_order(&ids, a, b));
            assert_eq!(got, want, "seed {seed}, point {i}");
        }
    }

    #[test]
    fn bad_radius_is_an_error() {
        let pts = [DVec3::ZERO];
        for r in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert!(RadiusGrid::new(&pts, &[0], r).is_err(), "radius {r}");
        }
    }
}
