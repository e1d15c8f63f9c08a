//! The generalized winding number of the oriented samples (Barill, Dickson,
//! Schmidt, Levin and Jacobson 2018, "Fast winding numbers for soups and
//! clouds"): `w(q) = sum_i a_i (x_i - q) . n_i / (4 pi |x_i - q|^3)`, about
//! 1 inside a closed surface and 0 outside, and smooth (harmonic) across
//! the places the scan missed, so its 1/2 level closes a hole the way the
//! surface around it runs. `--closed` takes the sign of every lattice
//! corner away from the samples from it ([`super::closed`]).
//!
//! The sum is evaluated Barnes-Hut style over a tree of cells ([`cells`]
//! gathers the leaves from the store in one pass): a cell far enough from
//! `q` counts as one dipole at its samples' centroid. Deviations from the
//! paper, and why:
//! - the leaves are cells of samples, not samples: the tree must sit in
//!   memory beside the tiles of an out-of-core run, so its size follows the
//!   surface's area in leaf cells, not the point count (a leaf closer to
//!   `q` than the opening rule allows still counts as one dipole; the
//!   corners that ask lie beyond the narrow band, at least two leaves from
//!   every sample, see [`super::closed`]);
//! - a sample's area `a_i` is its cell's area shared equally, the cell's
//!   area from the spread of its samples in their plane (`cells`), where
//!   the paper takes a Voronoi area in each sample's tangent plane: the
//!   cell's is found from sums alone, in one pass, whatever the density;
//! - first-order (dipole) expansions only: the sign is what is asked, far
//!   from the samples, where the second-order terms are small.

pub(crate) mod cells;
#[cfg(test)]
mod tests;

use glam::DVec3;
use std::f64::consts::PI;

/// A cell of the tree: its samples' centroid, their area-weighted normal
/// sum `sum a_i n_i`, and its children (a range of the level below).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Dipole {
    pub centroid: DVec3,
    pub moment: DVec3,
    pub area: f64,
    first_child: u32,
    children: u32,
}

/// A dipole cell is taken whole when `q` lies farther from its centroid
/// than this many times its side: cells seen under less than about 25
/// degrees (Barill et al. use 2 with second-order terms; the first-order
/// error falls with the square of the ratio).
const OPENING: f64 = 2.0;

/// Cells of the top level at most: the codes' bias splits the space at
/// the origin, so cells on both sides meet only at the top bit.
const MAX_ROOTS: usize = 8;

/// The tree: `levels[0]` the leaves (cells of side `leaf`), each level
/// above of cells twice the side, its children contiguous below it
/// (Morton order), the last level the roots.
#[derive(Clone, Debug, Default)]
pub(crate) struct WindingTree {
    leaf: f64,
    levels: Vec<Vec<Dipole>>,
}

impl WindingTree {
    /// The tree over leaf cells of side `leaf`, given as
    /// `(morton code, centroid, moment, area)` sorted by code.
    pub(crate) fn new(leaf: f64, leaves: Vec<(u64, Dipole)>) -> Self {
        let mut codes: Vec<u64> = leaves.iter().map(|l| l.0).collect();
        let mut levels = vec![leaves.into_iter().map(|l| l.1).collect::<Vec<_>>()];
        while levels.last().is_some_and(|l| l.len() > MAX_ROOTS) {
            let (parents, parent_codes) = parents_of(levels.last().expect("a level"), &codes);
            levels.push(parents);
            codes = parent_codes;
        }
        WindingTree { leaf, levels }
    }

    /// Leaf cells.
    #[cfg(test)]
    pub(crate) fn leaves(&self) -> usize {
        self.levels.first().map_or(0, Vec::len)
    }

    /// Whether a leaf cell meets the box `lo`..`hi` (a cell is found by
    /// its level's aligned cube round its centroid, which lies in it).
    pub(crate) fn any_within(&self, lo: DVec3, hi: DVec3) -> bool {
        let Some(top) = self.levels.len().checked_sub(1) else {
            return false;
        };
        let mut stack: Vec<(usize, u32)> = (0..self.levels[top].len() as u32)
            .map(|i| (top, i))
            .collect();
        while let Some((level, i)) = stack.pop() {
            let cell = &self.levels[level][i as usize];
            let side = self.leaf * f64::from(1u32 << level.min(31));
            let min = (cell.centroid / side).floor() * side;
            let max = min + DVec3::splat(side);
            if (0..3).any(|a| max[a] < lo[a] || min[a] > hi[a]) {
                continue;
            }
            if level == 0 {
                return true;
            }
            let children = cell.first_child..cell.first_child + cell.children;
            stack.extend(children.map(|c| (level - 1, c)));
        }
        false
    }

    /// The winding number at `q`.
    pub(crate) fn at(&self, q: DVec3) -> f64 {
        let Some(top) = self.levels.len().checked_sub(1) else {
            return 0.0;
        };
        let mut stack: Vec<(usize, u32)> = (0..self.levels[top].len() as u32)
            .rev()
            .map(|i| (top, i))
            .collect();
        let mut w = 0.0;
        while let Some((level, i)) = stack.pop() {
            let cell = &self.levels[level][i as usize];
            let side = self.leaf * f64::from(1u32 << level.min(31));
            let d = cell.centroid - q;
            if level == 0 || d.length_squared() > (OPENING * side).powi(2) {
                w += dipole(cell, d);
                continue;
            }
            let children = cell.first_child..cell.first_child + cell.children;
            stack.extend(children.rev().map(|c| (level - 1, c)));
        }
        w
    }
}

/// One dipole's share of the winding number, `d` from the query to it.
fn dipole(cell: &Dipole, d: DVec3) -> f64 {
    let r2 = d.length_squared();
    if r2 <= 0.0 {
        return 0.0;
    }
    cell.moment.dot(d) / (4.0 * PI * r2 * r2.sqrt())
}

/// The level above `level` (codes `codes`): consecutive cells sharing
/// `code >> 3` merged into one parent, with its sums.
fn parents_of(level: &[Dipole], codes: &[u64]) -> (Vec<Dipole>, Vec<u64>) {
    let (mut parents, mut parent_codes) = (Vec::new(), Vec::new());
    let mut start = 0;
    while start < level.len() {
        let code = codes[start] >> 3;
        let end = start + codes[start..].partition_point(|c| c >> 3 == code);
        parents.push(merged(&level[start..end], start as u32));
        parent_codes.push(code);
        start = end;
    }
    (parents, parent_codes)
}

/// One parent over `children` (whose first index is `first`): areas and
/// moments summed, the centroid area-weighted.
fn merged(children: &[Dipole], first: u32) -> Dipole {
    let area: f64 = children.iter().map(|c| c.area).sum();
    let moment = children.iter().map(|c| c.moment).sum();
    let weighted: DVec3 = children.iter().map(|c| c.centroid * c.area).sum();
    let centroid = if area > 0.0 {
        weighted / area
    } else {
        children.iter().map(|c| c.centroid).sum::<DVec3>() / children.len() as f64
    };
    Dipole {
        centroid,
        moment,
        area,
        first_child: first,
        children: children.len() as u32,
    }
}

impl Dipole {
    /// A leaf cell.
    pub(crate) fn leaf(centroid: DVec3, moment: DVec3, area: f64) -> Self {
        Dipole {
            centroid,
            moment,
            area,
            first_child: 0,
            children: 0,
        }
    }
}
