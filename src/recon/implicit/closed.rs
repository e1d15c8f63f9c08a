//! `--closed` by construction: every lattice corner gets a sign, so the
//! marching cubes' zero set has no boundary anywhere (paper 1 section 4.1
//! asks for a closed surface; a cube whose corners all have values cannot
//! leave a crack, and the case table's faces are decided by the face's own
//! four signs, so neighbouring cubes agree).
//!
//! A corner near the samples ([`Everywhere::near`]: within the band of an
//! occupied cube) takes the field's value, as in the open mode. Any other
//! corner takes the winding number of the samples ([`super::winding`]),
//! `w > 1/2` inside, interpolated from a coarse lattice of [`COARSE`]
//! cubes a side: a coarse corner near the samples carries the field's
//! value mapped onto `w`'s scale ([`from_field`]), any other the tree's
//! `w`. Where the data has a hole, `w`'s half level closes it as the
//! surface around it runs; far from the data every coarse cell has one
//! sign, and the cubes inside it none to draw.
//!
//! Every value is a function of its corner alone (the band, from the
//! samples within reach; the tree, global; the interpolation, from the
//! coarse cell below the corner), so the tiles agree on every shared
//! corner and the mesh is the same in any tiling.
//!
//! Deviation from paper 1, which marches the whole box and defines every
//! corner by the nearest plane: far from the samples that plane's sign is
//! the nearest sample's, which is wrong across a hole; the winding number
//! sees every sample at once.

use super::dilate::dilate;
use super::lattice::{edge_from_key, edge_key, Lattice, LatticeError};
use super::winding::WindingTree;
use crate::geom::Aabb;
use rayon::prelude::*;

/// Side of a coarse cell, in cubes: the winding number is evaluated at
/// one corner in `COARSE^3`.
pub(crate) const COARSE: i64 = 4;

/// Side of a super cell, in coarse cells ([`Supers`]): the coarse lattice
/// asked of the tree over the whole box grew with the volume (100M points
/// ran for hours).
const SUPER: i64 = 8;

/// Sign information for every corner of the lattice box.
pub(crate) struct Everywhere {
    pub tree: WindingTree,
    /// Lattice corners within the padded data box; every corner outside
    /// lies outside the surface.
    pub lo: [i64; 3],
    pub hi: [i64; 3],
}

impl Everywhere {
    /// Signs for the lattice `lattice` over data within `bounds`, padded by
    /// `pad` cubes beyond which nothing is drawn.
    pub(crate) fn new(tree: WindingTree, lattice: &Lattice, bounds: &Aabb, pad: i64) -> Self {
        let lo = lattice.cell_of(bounds.min).map(|c| c - pad);
        let hi = lattice.cell_of(bounds.max).map(|c| c + pad + 1);
        Everywhere { tree, lo, hi }
    }

    /// The super cells round the coarse box `coarse` (one more below, for
    /// corners on their faces): which are loud, and `w` at their corners.
    /// `reach` is how far from a sample, in cubes, the field rather than
    /// the winding number may decide.
    pub(crate) fn supers(&self, lattice: &Lattice, coarse: &CoarseBox, reach: i64) -> Supers {
        let lo = coarse.lo.map(|v| v.div_euclid(SUPER) - 1);
        let hi = [0, 1, 2].map(|a| (coarse.lo[a] + coarse.n[a]).div_euclid(SUPER) + 1);
        let n = [0, 1, 2].map(|a| hi[a] - lo[a] + 1);
        let side = COARSE * SUPER;
        let corner_w: Vec<f64> = grid(n)
            .collect::<Vec<_>>()
            .par_iter()
            .map(|i| self.exact_w(lattice, [0, 1, 2].map(|a| (lo[a] + i[a]) * side)))
            .collect();
        let mut supers = Supers {
            lo,
            n,
            corner_w,
            loud: Vec::new(),
        };
        supers.loud = grid(n.map(|v| v - 1))
            .collect::<Vec<_>>()
            .par_iter()
            .map(|i| {
                let cell = [0, 1, 2].map(|a| lo[a] + i[a]);
                supers.is_mixed(cell) || self.near_data(lattice, cell, reach)
            })
            .collect();
        supers
    }

    /// Whether a sample lies within `reach` cubes of super cell `cell`
    /// (asked of the global tree, so every tile gets the same answer).
    fn near_data(&self, lattice: &Lattice, cell: [i64; 3], reach: i64) -> bool {
        let side = COARSE * SUPER;
        let lo = lattice.corner(cell.map(|v| v * side - reach));
        let hi = lattice.corner(cell.map(|v| (v + 1) * side + reach));
        self.tree.any_within(lo, hi)
    }

    /// The winding number at lattice corner `c`: 0 outside the box.
    pub(crate) fn exact_w(&self, lattice: &Lattice, c: [i64; 3]) -> f64 {
        if (0..3).any(|a| c[a] < self.lo[a] || c[a] > self.hi[a]) {
            return 0.0;
        }
        self.tree.at(lattice.corner(c))
    }

    /// The coarse cells a tile whose owned cubes are `cubes` (a box of
    /// cube indices, half-open) needs: every corner of an owned cube lies
    /// in one, clipped to the box.
    pub(crate) fn coarse_box(&self, cubes: ([i64; 3], [i64; 3])) -> Option<CoarseBox> {
        let (lo, hi) = cubes;
        let mut b = CoarseBox {
            lo: [0; 3],
            n: [0; 3],
        };
        for a in 0..3 {
            let first = lo[a].max(self.lo[a]);
            let last = hi[a].min(self.hi[a]);
            if first >= last {
                return None;
            }
            b.lo[a] = first.div_euclid(COARSE);
            b.n[a] = last.div_euclid(COARSE) - b.lo[a] + 1;
        }
        Some(b)
    }
}

/// A box of coarse cells: `n` a side from coarse cell `lo`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct CoarseBox {
    pub lo: [i64; 3],
    pub n: [i64; 3],
}

impl CoarseBox {
    fn contains(&self, cell: [i64; 3]) -> bool {
        (0..3).all(|a| cell[a] >= self.lo[a] && cell[a] < self.lo[a] + self.n[a])
    }
}

/// `w` at the coarse corners a tile asks about, by key (of the corner's
/// coarse indices): only near loud super cells ([`Supers::busy_cells`]),
/// so a tile's coarse values follow the surface in it, not its volume (a
/// tile of few points can span half the box: at 100M points the dense
/// coarse box of every tile took the run to 1 GiB under `--mem 512MiB`).
pub(crate) struct CoarseValues {
    keys: Vec<u64>,
    w: Vec<f64>,
}

impl CoarseValues {
    /// The keys of the corners of coarse cells `cells` (keys, sorted).
    pub(crate) fn corners_of(cells: &[u64]) -> Result<Vec<u64>, LatticeError> {
        dilate(cells, 0..=1)
    }

    /// Lattice indices of the coarse corner of key `key`.
    pub(crate) fn corner(key: u64) -> [i64; 3] {
        edge_from_key(key).map_or([0; 3], |(c, _)| c.map(|v| v * COARSE))
    }

    /// Values `w` at the corners of keys `keys` (sorted).
    pub(crate) fn new(keys: Vec<u64>, w: Vec<f64>) -> Self {
        CoarseValues { keys, w }
    }

    fn at(&self, c: [i64; 3]) -> Option<f64> {
        let key = edge_key(c.map(|v| v.div_euclid(COARSE)), 0).ok()?;
        self.keys.binary_search(&key).ok().map(|i| self.w[i])
    }

    /// The cells of `cells` (keys) whose corner values are not all on one
    /// side of 1/2: the winding number's half level may pass through them.
    pub(crate) fn mixed_cells(&self, cells: &[u64]) -> Vec<[i64; 3]> {
        cells
            .iter()
            .filter_map(|&k| edge_from_key(k).ok().map(|(cell, _)| cell))
            .filter(|&cell| {
                let (mut any, mut all) = (false, true);
                for o in 0..8usize {
                    let c = [0, 1, 2].map(|a| (cell[a] + ((o >> a) & 1) as i64) * COARSE);
                    let inside = self.at(c).is_some_and(|w| w > 0.5);
                    any |= inside;
                    all &= inside;
                }
                any && !all
            })
            .collect()
    }

    /// `w` at fine corner `c`, trilinear in the coarse cell below it (a
    /// corner on a coarse face gets the same bits from every tile, since
    /// the cell is chosen by the corner alone); `None` when a corner of
    /// that cell was not asked about.
    pub(crate) fn interpolate(&self, c: [i64; 3]) -> Option<f64> {
        let base = c.map(|v| v.div_euclid(COARSE) * COARSE);
        let t = [0, 1, 2].map(|a| (c[a] - base[a]) as f64 / COARSE as f64);
        let mut sum = 0.0;
        for o in 0..8 {
            let corner = [0, 1, 2].map(|a| base[a] + ((o >> a) & 1) as i64 * COARSE);
            let weight: f64 = (0..3)
                .map(|a| if (o >> a) & 1 == 1 { t[a] } else { 1.0 - t[a] })
                .product();
            if weight > 0.0 {
                sum += weight * self.at(corner)?;
            }
        }
        Some(sum)
    }
}

/// Super cells of [`SUPER`] coarse cells a side: far from the samples the
/// winding number is smooth, and a super cell whose corners agree and
/// that no sample comes near is quiet: its coarse corners take `w`
/// interpolated from its corners. A coarse corner is asked of the tree
/// only where a super cell round it is loud.
pub(crate) struct Supers {
    lo: [i64; 3],
    n: [i64; 3],
    corner_w: Vec<f64>,
    loud: Vec<bool>,
}

impl Supers {
    fn corner_index(&self, i: [i64; 3]) -> Option<usize> {
        let ok = (0..3).all(|a| i[a] >= 0 && i[a] < self.n[a]);
        ok.then(|| (i[0] + self.n[0] * (i[1] + self.n[1] * i[2])) as usize)
    }

    fn cell_index(&self, cell: [i64; 3]) -> Option<usize> {
        let m = self.n.map(|v| v - 1);
        let i = [0, 1, 2].map(|a| cell[a] - self.lo[a]);
        let ok = (0..3).all(|a| i[a] >= 0 && i[a] < m[a]);
        ok.then(|| (i[0] + m[0] * (i[1] + m[1] * i[2])) as usize)
    }

    fn is_mixed(&self, cell: [i64; 3]) -> bool {
        let (mut any, mut all) = (false, true);
        for o in 0..8usize {
            let i = [0, 1, 2].map(|a| cell[a] - self.lo[a] + ((o >> a) & 1) as i64);
            let inside = self.corner_index(i).is_some_and(|k| self.corner_w[k] > 0.5);
            any |= inside;
            all &= inside;
        }
        any && !all
    }

    /// The coarse cells of `coarse` in or beside a loud super cell, as
    /// keys, sorted: with the cells round a near coarse corner
    /// ([`cells_round_near`]) the only ones that may be mixed (a quiet
    /// super cell's coarse corners are interpolated between corners on one
    /// side, except on a face it shares with a loud one), and the ones a
    /// cube near the samples interpolates in (a sample of the tree within
    /// reach makes its super cell loud; the cube's far corners may lie in
    /// the next).
    pub(crate) fn busy_cells(&self, coarse: &CoarseBox) -> Result<Vec<u64>, LatticeError> {
        let m = self.n.map(|v| v - 1);
        let mut cells = Vec::new();
        for (k, _) in self.loud.iter().enumerate().filter(|l| *l.1) {
            let k = k as i64;
            let sup = [k % m[0], (k / m[0]) % m[1], k / (m[0] * m[1])];
            let first = [0, 1, 2].map(|a| (self.lo[a] + sup[a]) * SUPER - 1);
            for i in grid([SUPER + 2; 3]) {
                let cell = [0, 1, 2].map(|a| first[a] + i[a]);
                if coarse.contains(cell) {
                    cells.push(edge_key(cell, 0)?);
                }
            }
        }
        cells.sort_unstable();
        cells.dedup();
        Ok(cells)
    }

    /// `w` at coarse corner `c` (lattice indices) away from the samples:
    /// the tree's if a super cell round it is loud (or unknown here), else
    /// interpolated in the super cell below it.
    pub(crate) fn coarse_w(&self, e: &Everywhere, lattice: &Lattice, c: [i64; 3]) -> f64 {
        let side = COARSE * SUPER;
        let base = c.map(|v| v.div_euclid(side));
        let on_face = c.map(|v| v.rem_euclid(side) == 0);
        for o in 0..8usize {
            let below = [0, 1, 2].map(|a| (o >> a) & 1 == 1);
            if (0..3).any(|a| below[a] && !on_face[a]) {
                continue;
            }
            let cell = [0, 1, 2].map(|a| base[a] - i64::from(below[a]));
            if self.cell_index(cell).is_none_or(|k| self.loud[k]) {
                return e.exact_w(lattice, c);
            }
        }
        let mut sum = 0.0;
        for o in 0..8usize {
            let i = [0, 1, 2].map(|a| base[a] - self.lo[a] + ((o >> a) & 1) as i64);
            let weight: f64 = (0..3)
                .map(|a| {
                    let t = (c[a] - base[a] * side) as f64 / side as f64;
                    if (o >> a) & 1 == 1 {
                        t
                    } else {
                        1.0 - t
                    }
                })
                .product();
            match self.corner_index(i) {
                Some(k) if weight > 0.0 => sum += weight * self.corner_w[k],
                _ => {}
            }
        }
        sum
    }
}

/// The coarse cells of `coarse` round every coarse corner among `near`
/// (corner keys, sorted), as keys, sorted: such a corner takes the field's
/// value, so its cells may be mixed even where the samples that made it
/// near are not in the tree (degenerate or unoriented ones) and no super
/// cell round it is loud.
pub(crate) fn cells_round_near(near: &[u64], coarse: &CoarseBox) -> Result<Vec<u64>, LatticeError> {
    let mut cells = Vec::new();
    for &key in near {
        let Ok((c, _)) = edge_from_key(key) else {
            continue;
        };
        if c.iter().any(|v| v.rem_euclid(COARSE) != 0) {
            continue;
        }
        for o in 0..8usize {
            let cell = [0, 1, 2].map(|a| c[a] / COARSE - ((o >> a) & 1) as i64);
            if coarse.contains(cell) {
                cells.push(edge_key(cell, 0)?);
            }
        }
    }
    cells.sort_unstable();
    cells.dedup();
    Ok(cells)
}

/// The indices of a box of `n` a side, x fastest.
fn grid(n: [i64; 3]) -> impl Iterator<Item = [i64; 3]> {
    let [nx, ny, nz] = n.map(|v| v.max(0));
    (0..nx * ny * nz).map(move |i| [i % nx, (i / nx) % ny, i / (nx * ny)])
}

/// Half-width of the field-to-winding map, in coarse cells: a field value
/// of one coarse cell outside reads as `w = 0`, one inside as `w = 1`.
fn scale(lattice: &Lattice) -> f64 {
    2.0 * COARSE as f64 * lattice.cell
}

/// The field's value `f` (positive outside) read as a winding number.
pub(crate) fn from_field(lattice: &Lattice, f: f64) -> f64 {
    (0.5 - f / scale(lattice)).clamp(0.0, 1.0)
}

/// A winding number read as a field value (positive outside), never
/// exactly 0, so a vertex never lands on a corner.
pub(crate) fn to_field(lattice: &Lattice, w: f64) -> f64 {
    let f = (0.5 - w) * scale(lattice);
    if f == 0.0 {
        f64::MIN_POSITIVE
    } else {
        f
    }
}

/// Corners near the samples: those of the cubes within `band` cubes of an
/// occupied cube (`occupied` sorted corner keys).
pub(crate) fn near_corners(occupied: &[u64], band: i64) -> Result<Vec<u64>, LatticeError> {
    dilate(occupied, -band..=band + 1)
}

/// Cubes with a corner near the samples: the band widened by one cube.
pub(crate) fn touching_cubes(occupied: &[u64], band: i64) -> Result<Vec<u64>, LatticeError> {
    dilate(occupied, -band - 1..=band + 1)
}

/// The cubes (keys, sorted) of `cells` (coarse cells).
pub(crate) fn cubes_of(cells: &[[i64; 3]]) -> Result<Vec<u64>, LatticeError> {
    let mut keys = Vec::with_capacity(cells.len() * (COARSE * COARSE * COARSE) as usize);
    for cell in cells {
        for o in 0..COARSE * COARSE * COARSE {
            let off = [o % COARSE, (o / COARSE) % COARSE, o / (COARSE * COARSE)];
            keys.push(edge_key([0, 1, 2].map(|a| cell[a] * COARSE + off[a]), 0)?);
        }
    }
    keys.sort_unstable();
    keys.dedup();
    Ok(keys)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::recon::implicit::winding::cells::Gather;
    use crate::synth::fibonacci_sphere;
    use glam::DVec3;

    /// The signs round a unit sphere of 20,000 samples (those `keep`
    /// keeps) on a lattice of cubes 0.01 a side, padded by 40 cubes.
    fn unit_sphere(keep: impl Fn(&DVec3) -> bool) -> (Lattice, Everywhere) {
        let lattice = Lattice::new(DVec3::ZERO, 0.01).expect("lattice");
        let mut g = Gather::new(0.05, 0.024);
        for p in fibonacci_sphere(DVec3::ZERO, 1.0, 20_000) {
            if keep(&p) {
                g.add(p, p.normalize()).expect("in range");
            }
        }
        let bounds = Aabb {
            min: DVec3::splat(-1.0),
            max: DVec3::splat(1.0),
        };
        let e = Everywhere::new(g.tree(), &lattice, &bounds, 40);
        (lattice, e)
    }

    /// A sphere of radius 100 cubes: super cells at its centre and far
    /// outside are quiet, and their interpolated `w` keeps the tree's side
    /// of 1/2; two tiles' boxes give the same bits at every shared corner.
    #[test]
    fn quiet_super_cells_keep_the_sign_and_agree_across_tiles() {
        let (lattice, e) = unit_sphere(|_| true);
        let whole = CoarseBox {
            lo: [-40; 3],
            n: [80; 3],
        };
        let left = CoarseBox {
            lo: [-40; 3],
            n: [40, 80, 80],
        };
        let reach = 8;
        let (sw, sl) = (
            e.supers(&lattice, &whole, reach),
            e.supers(&lattice, &left, reach),
        );
        assert!(sw.loud.iter().any(|l| !l), "no quiet super cell");
        let mut quiet = 0;
        let corners =
            grid(left.n.map(|n| n + 1)).map(|i| [0, 1, 2].map(|a| (left.lo[a] + i[a]) * COARSE));
        for c in corners.step_by(7) {
            let w = sw.coarse_w(&e, &lattice, c);
            assert_eq!(w.to_bits(), sl.coarse_w(&e, &lattice, c).to_bits(), "{c:?}");
            let r = lattice.corner(c).length();
            if (r - 1.0).abs() > 0.2 {
                assert_eq!(w > 0.5, r < 1.0, "{c:?}: w {w} at radius {r}");
            }
            quiet += usize::from(w != e.exact_w(&lattice, c));
        }
        assert!(quiet > 0, "no corner was interpolated");
    }

    /// The mixed coarse cells found on the busy cells alone (those near a
    /// loud super cell) are those of the whole box, every corner asked.
    #[test]
    fn busy_cells_hold_every_mixed_cell() {
        // A sphere with a cap missing: the half level closes it.
        let (lattice, e) = unit_sphere(|p| p.z < 0.8);
        let coarse = CoarseBox {
            lo: [-35, -35, 0],
            n: [70, 70, 35],
        };
        let supers = e.supers(&lattice, &coarse, 8);
        let mut all: Vec<u64> = grid(coarse.n)
            .map(|i| edge_key([0, 1, 2].map(|a| coarse.lo[a] + i[a]), 0).expect("key"))
            .collect();
        all.sort_unstable();
        let values = |cells: &[u64]| {
            let corners = CoarseValues::corners_of(cells).expect("keys");
            let w = corners
                .iter()
                .map(|&k| supers.coarse_w(&e, &lattice, CoarseValues::corner(k)))
                .collect();
            CoarseValues::new(corners, w)
        };
        let busy = supers.busy_cells(&coarse).expect("keys");
        assert!(
            busy.len() < all.len() / 2,
            "{} of {}",
            busy.len(),
            all.len()
        );
        let mut dense = values(&all).mixed_cells(&all);
        let mut sparse = values(&busy).mixed_cells(&busy);
        dense.sort_unstable();
        sparse.sort_unstable();
        assert!(!dense.is_empty(), "the open cap draws no half level");
        assert_eq!(dense, sparse);
    }
}
