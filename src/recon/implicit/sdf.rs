//! The signed distance of paper 1 section 2.5 (restatement step 5): for a
//! lattice corner `p`, the nearest sample `x_i` with oriented normal `n_i`
//! gives `f(p) = (p - x_i) . n_i`, defined only where the projection
//! `z = p - f(p) n_i` lies within `rho + delta` of the samples; otherwise
//! undefined, which is how open boundaries appear.
//!
//! Evaluated on one tile's loaded samples, the value is exact (ties by id) as
//! long as every distance it relied on fits in the loaded region; otherwise
//! the evaluation says by how much the margin falls short.

use crate::spatial::{KnnIndex, Neighbour};
use crate::tiling::TilePoints;
use glam::DVec3;

/// Samples with usable oriented normals, and their kNN index.
pub struct Samples<'a> {
    pub points: &'a [DVec3],
    pub normals: &'a [DVec3],
    pub index: &'a dyn KnnIndex,
}

/// The value at a corner, or how far the loaded region falls short.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Corner {
    Value(Option<f64>),
    Short(f64),
}

/// Nearest samples whose tangent planes are tried, nearest first, before a
/// corner is declared undefined.
///
/// Deviation from paper 1 section 2.5, which tries only the nearest sample:
/// beside a convex sharp edge (a roof edge of a building in a terrain scan)
/// the nearest sample may lie on the wall, whose plane, extended past the
/// edge, projects the corner into the air beyond `rho + delta` of any sample,
/// so the corner is undefined and a hole opens in the middle of the data.
/// A sample of the other face (the roof) projects it onto data. Beyond an
/// open boundary every nearby plane projects the corner beyond the boundary,
/// so open boundaries still appear.
pub const PLANES_TRIED: usize = 8;

/// Evaluates `f` at `p`; `limit` is `rho + delta` (infinite for `--closed`).
pub fn signed_distance(
    s: &Samples,
    tile: &TilePoints,
    p: DVec3,
    limit: f64,
    nbr: &mut Vec<Neighbour>,
) -> Corner {
    let want = if limit.is_infinite() { 1 } else { PLANES_TRIED };
    s.index.knn(p, want, None, nbr);
    let Some(last) = nbr.last() else {
        return Corner::Value(None);
    };
    // Fewer than `want` loaded: complete only if nothing lies beyond.
    let reach = if nbr.len() == want {
        last.dist2.sqrt()
    } else {
        f64::INFINITY
    };
    let room = tile.room(p);
    if reach > room {
        return Corner::Short(reach - room);
    }
    // `nbr` is reused by the projection queries: copy the candidates out.
    let mut candidates = [0u32; PLANES_TRIED];
    let count = nbr.len().min(PLANES_TRIED);
    for (c, m) in candidates.iter_mut().zip(nbr.iter()) {
        *c = m.index;
    }
    for &i in &candidates[..count] {
        let (x, n) = (s.points[i as usize], s.normals[i as usize]);
        let f = (p - x).dot(n);
        if limit.is_infinite() {
            return Corner::Value(Some(f));
        }
        match projection_on_data(s, tile, p - f * n, limit, nbr) {
            Ok(true) => return Corner::Value(Some(f)),
            Ok(false) => continue,
            Err(short) => return Corner::Short(short),
        }
    }
    Corner::Value(None)
}

/// Whether some sample lies within `limit` of `z`; `Err` with the shortfall
/// when the loaded region cannot tell.
fn projection_on_data(
    s: &Samples,
    tile: &TilePoints,
    z: DVec3,
    limit: f64,
    nbr: &mut Vec<Neighbour>,
) -> Result<bool, f64> {
    s.index.knn(z, 1, None, nbr);
    match nbr.first() {
        Some(m) if m.dist2.sqrt() < limit => Ok(true),
        // Nothing loaded within the limit: true only if nothing unloaded is.
        _ if tile.room(z) >= limit => Ok(false),
        _ => Err(limit - tile.room(z)),
    }
}
