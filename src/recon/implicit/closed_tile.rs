//! One tile of a `--closed` reconstruction ([`super::closed`]): which owned
//! cubes may hold the surface, and the value at each of their corners.
//!
//! The cubes: those with a corner near the samples (the band widened by
//! one cube, where the field's values meet the winding number's), and
//! those of every coarse cell whose corners disagree about inside (where
//! the winding number's half level runs, across holes). Any other cube
//! lies in a coarse cell of one sign, with no corner near the samples, so
//! its corners all share that sign and it holds nothing.

use super::closed::{
    cells_round_near, cubes_of, from_field, near_corners, to_field, touching_cubes, CoarseValues,
    Everywhere, Supers, COARSE,
};
use super::cubes::{corner_of, occupied, owned_cubes, owns};
use super::dilate::dilate;
use super::kernel::ImplicitKernel;
use super::refine::CornerValue;
use super::sdf::{Known, Samples};
use crate::pipeline::{KernelError, TileFault};
use crate::tiling::TilePoints;
use rayon::prelude::*;

/// A corner's value, or how far the loaded region falls short.
type Valued = Result<Option<Known>, f64>;

/// One `--closed` tile at work: the signs everywhere, the super cells over
/// its box, `w` at the coarse corners it asks about, and its samples with
/// the corners near them (keys, sorted).
struct Coarse<'a> {
    e: &'a Everywhere,
    supers: Supers,
    values: CoarseValues,
    near: &'a [u64],
    samples: &'a Samples<'a>,
    tile: &'a TilePoints,
}

impl ImplicitKernel {
    /// The owned cubes that may hold the surface, sorted, and the values
    /// at all their corners, sorted by key.
    pub(super) fn closed_cubes(
        &self,
        e: &Everywhere,
        samples: &Samples,
        tile: &TilePoints,
    ) -> Result<(Vec<[i64; 3]>, Vec<CornerValue>), KernelError> {
        let lattice = &self.lattice;
        let occupied = occupied(lattice, samples.points)?;
        let near = near_corners(&occupied, self.band).map_err(KernelError::failed)?;
        let Some(coarse_box) = e.coarse_box(owned_cubes(lattice, &tile.core)) else {
            return Ok((Vec::new(), Vec::new()));
        };
        let supers = e.supers(lattice, &coarse_box, self.band + COARSE + 2);
        let mut cells = supers
            .busy_cells(&coarse_box)
            .map_err(KernelError::failed)?;
        cells.extend(cells_round_near(&near, &coarse_box).map_err(KernelError::failed)?);
        cells.sort_unstable();
        cells.dedup();
        let corners = CoarseValues::corners_of(&cells).map_err(KernelError::failed)?;
        let mut coarse = Coarse {
            e,
            supers,
            values: CoarseValues::new(Vec::new(), Vec::new()),
            near: &near,
            samples,
            tile,
        };
        let w = self.coarse_values(&coarse, &corners)?;
        coarse.values = CoarseValues::new(corners, w);
        let mut keys = touching_cubes(&occupied, self.band).map_err(KernelError::failed)?;
        let mixed = coarse.values.mixed_cells(&cells);
        keys.extend(cubes_of(&mixed).map_err(KernelError::failed)?);
        keys.par_sort_unstable();
        keys.dedup();
        keys.retain(|&k| owns(lattice, &tile.core, corner_of(k)));
        let cubes: Vec<[i64; 3]> = keys.iter().map(|&k| corner_of(k)).collect();
        let values = self.closed_corner_values(&coarse, &keys)?;
        Ok((cubes, values))
    }

    /// The winding number at the coarse corners of keys `corners`.
    fn coarse_values(&self, coarse: &Coarse, corners: &[u64]) -> Result<Vec<f64>, KernelError> {
        let valued: Vec<Result<f64, f64>> = corners
            .par_iter()
            .map_init(Vec::new, |nbr, &k| {
                self.coarse_w(coarse, CoarseValues::corner(k), nbr)
            })
            .collect::<Result<_, _>>()?;
        settle(valued, coarse.tile.margin)
    }

    /// The winding number at coarse corner `c`: near the samples the
    /// field's value read on its scale, elsewhere the tree's (or the super
    /// cell's interpolation).
    fn coarse_w(
        &self,
        coarse: &Coarse,
        c: [i64; 3],
        nbr: &mut Vec<crate::spatial::Neighbour>,
    ) -> Result<Result<f64, f64>, KernelError> {
        let key = super::lattice::edge_key(c, 0).map_err(KernelError::failed)?;
        if coarse.near.binary_search(&key).is_err() {
            return Ok(Ok(coarse.supers.coarse_w(coarse.e, &self.lattice, c)));
        }
        Ok(self
            .field_at(coarse.samples, coarse.tile, c, nbr)
            .map(|f| from_field(&self.lattice, f.map_or(0.0, Known::value))))
    }

    /// Values at the corners of `cubes` (keys, sorted): the field's near
    /// the samples, else the winding number interpolated in the coarse
    /// cell below the corner.
    fn closed_corner_values(
        &self,
        coarse: &Coarse,
        cubes: &[u64],
    ) -> Result<Vec<CornerValue>, KernelError> {
        let keys = dilate(cubes, 0..=1).map_err(KernelError::failed)?;
        let valued: Vec<Valued> = keys
            .par_iter()
            .map_init(Vec::new, |nbr, &key| -> Result<_, KernelError> {
                let c = corner_of(key);
                if coarse.near.binary_search(&key).is_ok() {
                    return Ok(self.field_at(coarse.samples, coarse.tile, c, nbr));
                }
                let at = match coarse.values.interpolate(c) {
                    Some(w) => Ok(w),
                    None => self.interpolate_asking(coarse, c, nbr)?,
                };
                Ok(at.map(|w| Some(Known::Winding(to_field(&self.lattice, w)))))
            })
            .collect::<Result<_, _>>()?;
        let values = settle(valued, coarse.tile.margin)?;
        Ok(keys.into_iter().zip(values).collect())
    }

    /// [`CoarseValues::interpolate`] for a corner whose coarse cell was
    /// not asked about (a cube near samples the tree leaves out, degenerate
    /// or unoriented, whose super cell is quiet): each coarse corner
    /// found as [`Self::coarse_w`] finds it, so the value is the same.
    fn interpolate_asking(
        &self,
        coarse: &Coarse,
        c: [i64; 3],
        nbr: &mut Vec<crate::spatial::Neighbour>,
    ) -> Result<Result<f64, f64>, KernelError> {
        let base = c.map(|v| v.div_euclid(COARSE));
        let key = super::lattice::edge_key(base, 0).map_err(KernelError::failed)?;
        let corners = CoarseValues::corners_of(&[key]).map_err(KernelError::failed)?;
        let mut w = Vec::with_capacity(8);
        for &k in &corners {
            match self.coarse_w(coarse, CoarseValues::corner(k), nbr)? {
                Ok(v) => w.push(v),
                Err(short) => return Ok(Err(short)),
            }
        }
        let cell = CoarseValues::new(corners, w);
        cell.interpolate(c)
            .map(Ok)
            .ok_or(KernelError::Failed(TileFault::CoarseCorners { corner: c }))
    }

    /// The field's value at corner `c`, or the loaded region's shortfall.
    fn field_at(
        &self,
        samples: &Samples,
        tile: &TilePoints,
        c: [i64; 3],
        nbr: &mut Vec<crate::spatial::Neighbour>,
    ) -> Valued {
        let p = self.lattice.corner(c);
        let (corner, fit) = self.field.corner(samples, tile, p, self.limit, nbr);
        corner.known(fit)
    }
}

/// The values, or a reload when one fell short of the loaded region.
fn settle<T>(valued: Vec<Result<T, f64>>, margin: f64) -> Result<Vec<T>, KernelError> {
    let short = valued
        .iter()
        .filter_map(|v| v.as_ref().err())
        .fold(0.0f64, |m, &s| m.max(s));
    KernelError::unless_short(short, margin)?;
    Ok(valued.into_iter().filter_map(Result::ok).collect())
}
