//! Exact fixed-radius search over one set of points (a tile's points, its
//! feature points, its enhanced points): cells of side `cell`, so a ball of
//! radius up to `cell` around any position meets at most the 27 cells around
//! the position's cell (and a larger one the cells within its reach).
//!
//! Answers come in a canonical order that no tiling changes: cells in a
//! fixed order around the query (the lattice is anchored at the store
//! origin), and by input id within a cell; [`BallGrid::nearest_first`]
//! sorts them into the project's neighbour order, (squared distance, id),
//! for the callers that take the nearest. Distances are computed by one
//! formula, so a tile and the whole cloud see the same neighbourhood, in
//! the same order, for a point whose ball is loaded: sums over it are the
//! same to the last bit. (Sorting every answer cost 14 % of the dragon's
//! whole `features` run.) The cell map is only looked up, never iterated,
//! so its order cannot leak into results. (`normals::sources`' radius grid answers for indexed points
//! at one radius; the feature stages query arbitrary positions at radii up
//! to the cell.)

use crate::spatial::Neighbour;
use glam::DVec3;
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

/// A fixed-radius index over `points` (tie keys `ids`, or the points'
/// indices for [`BallGrid::indexed`]).
pub struct BallGrid<'a> {
    points: &'a [DVec3],
    ids: Option<&'a [u64]>,
    inv: f64,
    /// Point indices sorted by cell; `cells` maps a cell to its range.
    order: Vec<u32>,
    cells: HashMap<u64, (u32, u32), BuildHasherDefault<CellHasher>>,
}

impl<'a> BallGrid<'a> {
    /// `None` when `cell` is not a positive finite size or the set is too
    /// large for u32 indices.
    pub fn new(points: &'a [DVec3], ids: &'a [u64], cell: f64) -> Option<Self> {
        if points.len() != ids.len() {
            return None;
        }
        Self::build(points, Some(ids), cell)
    }

    /// A grid whose tie key is each point's index in `points` (the seam
    /// join's line vertices, already in canonical order): no id array,
    /// 8 bytes per vertex less where all of a run's lines are held.
    pub fn indexed(points: &'a [DVec3], cell: f64) -> Option<Self> {
        Self::build(points, None, cell)
    }

    fn build(points: &'a [DVec3], ids: Option<&'a [u64]>, cell: f64) -> Option<Self> {
        if !(cell.is_finite() && cell > 0.0) {
            return None;
        }
        if points.len() >= u32::MAX as usize {
            return None;
        }
        let inv = 1.0 / cell;
        // By cell, then id: the canonical order within a cell.
        let mut keyed: Vec<(u64, u64, u32)> = points
            .iter()
            .enumerate()
            .map(|(i, p)| {
                (
                    pack(cell_of(*p, inv)),
                    ids.map_or(i as u64, |ids| ids[i]),
                    i as u32,
                )
            })
            .collect();
        keyed.sort_unstable();
        let mut cells = HashMap::with_capacity_and_hasher(keyed.len() / 4, Default::default());
        cells.extend(key_runs(&keyed, |e| e.0));
        Some(BallGrid {
            points,
            ids,
            inv,
            order: keyed.into_iter().map(|(_, _, i)| i).collect(),
            cells,
        })
    }

    pub fn points(&self) -> &'a [DVec3] {
        self.points
    }

    fn id(&self, index: u32) -> u64 {
        self.ids.map_or(u64::from(index), |ids| ids[index as usize])
    }

    /// Every point within `radius` (at most 8 cells) of `q`, except
    /// `exclude`, in the canonical order (module doc), into `out`.
    pub fn within(&self, q: DVec3, radius: f64, exclude: Option<u32>, out: &mut Vec<Neighbour>) {
        out.clear();
        let r2 = radius * radius;
        let c = cell_of(q, self.inv);
        // Cells each way that a ball of `radius` can reach (a far larger
        // radius than the cell is the caller's mistake, and is capped).
        let span = (radius * self.inv).ceil().clamp(1.0, 8.0) as i64;
        // Cells whose box lies beyond the radius are skipped (a third of
        // the 27 for a radius of one cell): exact, they hold no answer.
        // Not near the clamp, where a key no longer stands for its box.
        let exact = c.iter().all(|v| v.abs() < CLAMP - 2 * span - 2);
        let f = [q.x, q.y, q.z].map(|v| v * self.inv);
        let gap = |a: usize, d: i64| -> f64 {
            let frac = f[a] - c[a] as f64;
            match d {
                0 => 0.0,
                d if d > 0 => (d as f64 - frac).max(0.0),
                d => (frac - d as f64 - 1.0).max(0.0),
            }
        };
        let rr = if exact {
            (radius * self.inv).powi(2) * (1.0 + 1e-9) + 1e-12
        } else {
            f64::INFINITY
        };
        for dz in -span..=span {
            let gz = gap(2, dz).powi(2);
            if gz > rr {
                continue;
            }
            for dy in -span..=span {
                let gyz = gz + gap(1, dy).powi(2);
                if gyz > rr {
                    continue;
                }
                for dx in -span..=span {
                    if gyz + gap(0, dx).powi(2) > rr {
                        continue;
                    }
                    let key = pack([c[0] + dx, c[1] + dy, c[2] + dz]);
                    let Some(&(s, e)) = self.cells.get(&key) else {
                        continue;
                    };
                    for &j in &self.order[s as usize..e as usize] {
                        let d2 = (self.points[j as usize] - q).length_squared();
                        if d2 <= r2 && Some(j) != exclude {
                            out.push(Neighbour {
                                dist2: d2,
                                index: j,
                            });
                        }
                    }
                }
            }
        }
    }

    /// [`BallGrid::within`] sorted by (dist2, id): nearest first.
    pub fn nearest_first(
        &self,
        q: DVec3,
        radius: f64,
        exclude: Option<u32>,
        out: &mut Vec<Neighbour>,
    ) {
        self.within(q, radius, exclude, out);
        out.sort_unstable_by(|a, b| {
            a.dist2
                .total_cmp(&b.dist2)
                .then(self.id(a.index).cmp(&self.id(b.index)))
        });
    }
}

/// The runs of equal keys in `sorted` (entries sorted by `key`): each key
/// with the range of its entries, as a cell map over points sorted by
/// cell holds them.
pub(crate) fn key_runs<'a, T, K: PartialEq>(
    sorted: &'a [T],
    key: impl Fn(&T) -> K + Copy + 'a,
) -> impl Iterator<Item = (K, (u32, u32))> + 'a {
    let mut start = 0u32;
    sorted
        .chunk_by(move |a, b| key(a) == key(b))
        .map(move |run| {
            let first = start;
            start += run.len() as u32;
            (key(&run[0]), (first, start))
        })
}

/// Cell coordinates, clamped to 21 bits each side so that they pack into a
/// u64 key (a tile spans far fewer cells; clamping only merges cells beyond
/// +-2^20 cells from the origin, which stays exact because every candidate
/// is still tested by distance).
fn cell_of(p: DVec3, inv: f64) -> [i64; 3] {
    const LIM: f64 = CLAMP as f64;
    [p.x, p.y, p.z].map(|c| (c * inv).floor().clamp(-LIM, LIM) as i64)
}

/// Cell coordinates are clamped to +-`CLAMP` (see [`cell_of`]).
const CLAMP: i64 = 1 << 20;

fn pack(c: [i64; 3]) -> u64 {
    let f = |v: i64| ((v + (1 << 21)) as u64) & ((1 << 22) - 1);
    f(c[0]) | f(c[1]) << 22 | f(c[2]) << 44
}

/// A multiplicative hash for packed cell keys (the std SipHash costs more
/// than the distance tests of a query's 27 cells).
#[derive(Default)]
pub struct CellHasher(u64);

impl Hasher for CellHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for b in bytes {
            self.0 = (self.0.rotate_left(5) ^ u64::from(*b)).wrapping_mul(0x517c_c1b7_2722_0a95);
        }
    }
    fn write_u64(&mut self, v: u64) {
        self.0 = (v ^ (v >> 29)).wrapping_mul(0x9e37_79b9_7f4a_7c15);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    #[test]
    fn indexed_answers_as_ids_equal_to_the_indices() {
        let mut rng = Rng::new(9);
        // Duplicates, so the tie key decides an order.
        let points: Vec<DVec3> = (0..400)
            .map(|i| match i % 7 {
                0 => DVec3::splat(0.5),
                _ => DVec3::new(rng.uniform(), rng.uniform(), rng.uniform()),
            })
            .collect();
        let ids: Vec<u64> = (0..points.len() as u64).collect();
        let (a, b) = (
            BallGrid::new(&points, &ids, 0.1).unwrap(),
            BallGrid::indexed(&points, 0.1).unwrap(),
        );
        let (mut fa, mut fb) = (Vec::new(), Vec::new());
        for q in points.iter().step_by(3) {
            a.nearest_first(*q, 0.15, None, &mut fa);
            b.nearest_first(*q, 0.15, None, &mut fb);
            assert_eq!(fa, fb);
            a.within(*q, 0.1, Some(0), &mut fa);
            b.within(*q, 0.1, Some(0), &mut fb);
            assert_eq!(fa, fb);
        }
    }

    #[test]
    fn matches_brute_force_with_ties() {
        let seed = 5;
        let mut rng = Rng::new(seed);
        let mut points: Vec<DVec3> = (0..600)
            .map(|_| DVec3::new(rng.uniform(), rng.uniform(), rng.uniform() * 0.1))
            .collect();
        // Exact ties: duplicates at one spot.
        points.extend([DVec3::new(0.5, 0.5, 0.05); 4]);
        let ids: Vec<u64> = (0..points.len() as u64).map(|i| (i * 37) % 604).collect();
        let grid = BallGrid::new(&points, &ids, 0.08).unwrap();
        let mut got = Vec::new();
        for q in points.iter().take(200).chain([&DVec3::new(0.5, 0.5, 0.05)]) {
            for r in [0.02, 0.05, 0.08, 0.15] {
                grid.nearest_first(*q, r, None, &mut got);
                let mut want: Vec<(f64, u64)> = points
                    .iter()
                    .zip(&ids)
                    .map(|(p, id)| ((*p - *q).length_squared(), *id))
                    .filter(|(d, _)| *d <= r * r)
                    .collect();
                want.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
                let got: Vec<(f64, u64)> = got
                    .iter()
                    .map(|n| (n.dist2, ids[n.index as usize]))
                    .collect();
                assert_eq!(got, want, "seed {seed}, query {q}, radius {r}");
            }
        }
    }

    #[test]
    fn the_order_does_not_depend_on_how_points_are_listed() {
        let mut rng = Rng::new(8);
        let points: Vec<DVec3> = (0..500).map(|_| rng.unit_vector()).collect();
        let ids: Vec<u64> = (0..500u64).map(|i| i * 3 + 1).collect();
        // The same points listed backwards, with 100 others mixed in.
        let mut other: Vec<(DVec3, u64)> = points
            .iter()
            .copied()
            .zip(ids.iter().copied())
            .rev()
            .collect();
        other.extend((0..100).map(|i| (rng.unit_vector() * 3.0, 10_000 + i)));
        let (op, oi): (Vec<DVec3>, Vec<u64>) = other.into_iter().unzip();
        let a = BallGrid::new(&points, &ids, 0.3).unwrap();
        let b = BallGrid::new(&op, &oi, 0.3).unwrap();
        let (mut fa, mut fb) = (Vec::new(), Vec::new());
        for q in points.iter().take(50) {
            a.within(*q, 0.3, None, &mut fa);
            b.within(*q, 0.3, None, &mut fb);
            let ia: Vec<u64> = fa.iter().map(|n| ids[n.index as usize]).collect();
            let ib: Vec<u64> = fb.iter().map(|n| oi[n.index as usize]).collect();
            assert_eq!(ia, ib, "query {q}");
        }
    }
}
