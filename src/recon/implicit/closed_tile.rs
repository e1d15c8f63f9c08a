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
    cubes_of, from_field, near_corners, owned_cubes, to_field, touching_cubes, CoarseBox,
    Everywhere, COARSE,
};
use super::dilate::dilate;
use super::kernel::{corner_of, occupied, owns, ImplicitKernel};
use super::refine::CornerValue;
use super::sdf::{Known, Samples};
use crate::pipeline::KernelError;
use crate::tiling::TilePoints;
use rayon::prelude::*;

/// A corner's value, or how far the loaded region falls short.
type Valued = Result<Option<Known>, f64>;

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
        let Some(coarse) = e.coarse_box(owned_cubes(lattice, &tile.core)) else {
            return Ok((Vec::new(), Vec::new()));
        };
        let w = self.coarse_values(e, &coarse, &near, samples, tile)?;
        let mut keys = touching_cubes(&occupied, self.band).map_err(KernelError::failed)?;
        keys.extend(cubes_of(&coarse.mixed_cells(&w)).map_err(KernelError::failed)?);
        keys.par_sort_unstable();
        keys.dedup();
        keys.retain(|&k| owns(lattice, &tile.core, corner_of(k)));
        let cubes: Vec<[i64; 3]> = keys.iter().map(|&k| corner_of(k)).collect();
        let corners = self.closed_corner_values(&coarse, &w, &near, &keys, samples, tile)?;
        Ok((cubes, corners))
    }

    /// The winding number at every corner of `coarse`: near the samples the
    /// field's value read on its scale, elsewhere the tree's.
    fn coarse_values(
        &self,
        e: &Everywhere,
        coarse: &CoarseBox,
        near: &[u64],
        samples: &Samples,
        tile: &TilePoints,
    ) -> Result<Vec<f64>, KernelError> {
        let corners: Vec<[i64; 3]> = coarse.corners().collect();
        let supers = e.supers(&self.lattice, coarse, self.band + COARSE + 2);
        let valued: Vec<Result<f64, f64>> = corners
            .par_iter()
            .map_init(Vec::new, |nbr, &c| -> Result<_, KernelError> {
                let key = super::lattice::edge_key(c, 0).map_err(KernelError::failed)?;
                if near.binary_search(&key).is_err() {
                    return Ok(Ok(supers.coarse_w(e, &self.lattice, c)));
                }
                Ok(self
                    .field_at(samples, tile, c, nbr)
                    .map(|f| from_field(&self.lattice, f.map_or(0.0, Known::value))))
            })
            .collect::<Result<_, _>>()?;
        settle(valued, tile.margin)
    }

    /// Values at the corners of `cubes` (keys, sorted): the field's near
    /// the samples, else the winding number interpolated in `coarse`.
    fn closed_corner_values(
        &self,
        coarse: &CoarseBox,
        w: &[f64],
        near: &[u64],
        cubes: &[u64],
        samples: &Samples,
        tile: &TilePoints,
    ) -> Result<Vec<CornerValue>, KernelError> {
        let keys = dilate(cubes, 0..=1).map_err(KernelError::failed)?;
        let valued: Vec<Valued> = keys
            .par_iter()
            .map_init(Vec::new, |nbr, &key| -> Result<_, KernelError> {
                let c = corner_of(key);
                if near.binary_search(&key).is_ok() {
                    return Ok(self.field_at(samples, tile, c, nbr));
                }
                let at = coarse.interpolate(w, c).ok_or_else(|| {
                    KernelError::Failed(format!("corner {c:?} lies outside the coarse box"))
                })?;
                Ok(Ok(Some(Known::Winding(to_field(&self.lattice, at)))))
            })
            .collect::<Result<_, _>>()?;
        let values = settle(valued, tile.margin)?;
        Ok(keys.into_iter().zip(values).collect())
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
        self.field.corner(samples, tile, p, self.limit, nbr).known()
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
