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

/// Evaluates `f` at `p`; `limit` is `rho + delta` (infinite for `--closed`).
pub fn signed_distance(
    s: &Samples,
    tile: &TilePoints,
    p: DVec3,
    limit: f64,
    nbr: &mut Vec<Neighbour>,
) -> Corner {
    s.index.knn(p, 1, None, nbr);
    let Some(near) = nbr.first().copied() else {
        return Corner::Value(None);
    };
    let reach = near.dist2.sqrt();
    let room = tile.room(p);
    if reach > room {
        return Corner::Short(reach - room);
    }
    let (x, n) = (
        s.points[near.index as usize],
        s.normals[near.index as usize],
    );
    let f = (p - x).dot(n);
    if limit.is_infinite() {
        return Corner::Value(Some(f));
    }
    let z = p - f * n;
    s.index.knn(z, 1, None, nbr);
    match nbr.first() {
        Some(m) if m.dist2.sqrt() < limit => Corner::Value(Some(f)),
        // Nothing loaded within the limit: true only if nothing unloaded is.
        _ if tile.room(z) >= limit => Corner::Value(None),
        _ => Corner::Short(limit - tile.room(z)),
    }
}
