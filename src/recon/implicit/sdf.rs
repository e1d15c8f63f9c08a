//! The signed distance of paper 1 section 2.5 (restatement step 5): for a
//! lattice corner `p`, the nearest sample `x_i` with oriented normal `n_i`
//! gives `f(p) = (p - x_i) . n_i`, defined only where the projection
//! `z = p - f(p) n_i` lies within `rho + delta` of the samples; otherwise
//! undefined, which is how open boundaries appear. For a closed surface
//! (`--closed`, paper 1 section 4.1) every corner is defined, and `f`
//! averages the planes of many nearest samples (`averaged_planes`).
//!
//! Evaluated on one tile's loaded samples, the value is exact (ties by id) as
//! long as every distance it relied on fits in the loaded region; otherwise
//! the evaluation says by how much the margin falls short.

use crate::spatial::brute::dist2;
use crate::spatial::grid::GridIndex;
use crate::spatial::{KnnIndex, Neighbour};
use crate::tiling::TilePoints;
use glam::DVec3;

/// Samples with usable oriented normals, and their kNN index.
pub(crate) struct Samples<'a> {
    pub points: &'a [DVec3],
    pub normals: &'a [DVec3],
    pub index: &'a GridIndex<'a>,
}

/// The value at a corner, or how far the loaded region falls short.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Corner {
    Value(Option<f64>),
    /// A value whose projection lies off the data (open surfaces): the
    /// corner closes a cube only beside a corner on the data, so the mesh
    /// ends inside the cubes the data's edge crosses.
    Beyond(f64),
    Short(f64),
}

impl Corner {
    /// The value as the kernel keeps it, with the sphere the field fitted
    /// there, or the loaded region's shortfall.
    pub(crate) fn known(self, fit: Fit) -> Result<Option<Known>, f64> {
        match self {
            Corner::Value(f) => Ok(f.map(|f| Known::OnData(f, fit))),
            Corner::Beyond(f) => Ok(Some(Known::Beyond(f, fit))),
            Corner::Short(s) => Err(s),
        }
    }
}

/// The sphere the field fitted at a corner, normalised to a distance: at
/// `corner + d` it gives `value + gradient . d + quadratic |d|^2`
/// ([`super::mls`]). Kept so a cut edge's root is found from the spheres at
/// its two ends, with no evaluation of its own ([`super::refine`]). The
/// default, a zero gradient, is no sphere (paper 1's field, which places
/// vertices by linear interpolation). f32: the sphere is used within a
/// cell of its corner, where its 7 digits lie far below any scan's noise.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Fit {
    pub gradient: [f32; 3],
    pub quadratic: f32,
}

/// A corner's value as the kernel keeps it, and whether its projection
/// lies on the data ([`Corner::Beyond`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Known {
    OnData(f64, Fit),
    Beyond(f64, Fit),
    /// Away from the samples with `--closed`: the winding number's sign
    /// as a value ([`super::closed`]); the field's root is not sought on
    /// an edge that ends here.
    Winding(f64),
}

impl Known {
    pub(crate) fn value(self) -> f64 {
        match self {
            Known::OnData(f, _) | Known::Beyond(f, _) | Known::Winding(f) => f,
        }
    }

    /// The sphere fitted at the corner, if the field fitted one.
    pub(crate) fn fit(self) -> Option<Fit> {
        match self {
            Known::OnData(_, fit) | Known::Beyond(_, fit) => Some(fit),
            Known::Winding(_) => None,
        }
    }
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
pub(crate) const PLANES_TRIED: usize = 8;

/// Planes averaged at each corner of a closed surface (see
/// `averaged_planes`).
pub(crate) const CLOSED_PLANES: usize = 64;

/// Width of the averaging weight, as a share of the distance to the
/// farthest of the [`CLOSED_PLANES`] samples.
const CLOSED_WIDTH: f64 = 0.8;

/// Evaluates `f` at `p`; `limit` is `rho + delta` (infinite for `--closed`).
///
/// The nearest sample's plane is tried first, from a single-nearest query;
/// only when its projection misses the data (boundaries, sharp edges: a few
/// per cent of the corners) are the [`PLANES_TRIED`] nearest fetched. The
/// nearest is the first of those in the same (distance, id) order, so the
/// value is the same as trying them all from one query.
pub(crate) fn signed_distance(
    s: &Samples,
    tile: &TilePoints,
    p: DVec3,
    limit: f64,
    nbr: &mut Vec<Neighbour>,
) -> Corner {
    if limit.is_infinite() {
        return averaged_planes(s, tile, p, nbr);
    }
    let nearest = match nearest_planes(s, tile, p, 1, nbr) {
        Ok(Some((c, _))) => c[0],
        Ok(None) => return Corner::Value(None),
        Err(short) => return Corner::Short(short),
    };
    match try_plane(s, tile, p, nearest, limit, nbr) {
        Ok(Some(f)) => return Corner::Value(Some(f)),
        Ok(None) => {}
        Err(short) => return Corner::Short(short),
    }
    let (candidates, count) = match nearest_planes(s, tile, p, PLANES_TRIED, nbr) {
        Ok(Some(c)) => c,
        Ok(None) => return Corner::Value(None),
        Err(short) => return Corner::Short(short),
    };
    for &i in candidates[..count].iter().skip(1) {
        match try_plane(s, tile, p, i, limit, nbr) {
            Ok(Some(f)) => return Corner::Value(Some(f)),
            Ok(None) => continue,
            Err(short) => return Corner::Short(short),
        }
    }
    Corner::Value(None)
}

/// `f` for a closed surface: the plane values of the [`CLOSED_PLANES`]
/// nearest samples, averaged with Gaussian weights `exp(-d^2 / h^2)`, `h` =
/// [`CLOSED_WIDTH`] x the farthest one's distance.
///
/// Deviation from paper 1 sections 2.5 and 4.1, which take the nearest
/// sample's plane alone: with every corner defined, one mis-oriented sample
/// (at thin parts, where orientation is ill-posed: 0.6 % of the dragon's)
/// gives the wrong sign to its whole Voronoi cell, which reaches out of the
/// narrow band, so the surface leaks through the band's edge (a hole) or
/// bulges out with it. Many planes outvote it, and the width grows with the
/// distance to the data, so corners far from it average over a wide patch
/// while corners near it keep a local fit (the implicit MLS surface of
/// Kolluri 2005, with an adaptive width). 1M dragon samples, `--closed`:
/// 29 components and 34 boundary loops with the nearest plane, 2 and 1
/// with 64 averaged planes; mean distance to the dragon 0.122 / 0.152
/// spacings (mesh to reference / back) became 0.094 / 0.105.
/// The sum runs in (distance, id) order, so it is the same in every tiling.
fn averaged_planes(s: &Samples, tile: &TilePoints, p: DVec3, nbr: &mut Vec<Neighbour>) -> Corner {
    s.index.knn(p, CLOSED_PLANES, None, nbr);
    let Some(farthest) = nbr.last() else {
        return Corner::Value(None);
    };
    if let Err(short) = complete(tile, p, nbr, CLOSED_PLANES) {
        return Corner::Short(short);
    }
    let h2 = CLOSED_WIDTH * CLOSED_WIDTH * farthest.dist2;
    let (mut weights, mut sum) = (0.0, 0.0);
    for m in nbr.iter() {
        // All samples at `p` itself (h = 0): their plane values are 0.
        let w = if h2 > 0.0 { (-m.dist2 / h2).exp() } else { 1.0 };
        weights += w;
        sum += w * plane_value(s, m.index, p);
    }
    Corner::Value(Some(sum / weights))
}

/// The `want` (at most [`PLANES_TRIED`]) nearest samples of `p` (indices
/// into `s`) and their count; `None` when nothing is loaded, `Err` with the
/// shortfall when the loaded region cannot tell.
fn nearest_planes(
    s: &Samples,
    tile: &TilePoints,
    p: DVec3,
    want: usize,
    nbr: &mut Vec<Neighbour>,
) -> Result<Option<([u32; PLANES_TRIED], usize)>, f64> {
    // The previous query's answer (corners come in lattice order, so it is
    // usually next door) starts a single-nearest search bounded.
    if want == 1 {
        let previous = nbr.first().map(|n| n.index);
        nearest(s, p, previous, nbr);
    } else {
        s.index.knn(p, want, None, nbr);
    }
    if nbr.is_empty() {
        return Ok(None);
    }
    complete(tile, p, nbr, want)?;
    // `nbr` is reused by the projection queries: copy the candidates out.
    let mut candidates = [0u32; PLANES_TRIED];
    for (c, m) in candidates.iter_mut().zip(nbr.iter()) {
        *c = m.index;
    }
    Ok(Some((candidates, nbr.len().min(PLANES_TRIED))))
}

/// Whether `nbr`, the `want` nearest loaded samples of `p`, are the `want`
/// nearest of all; `Err` with the shortfall of the loaded region if not.
/// Fewer than `want` loaded are complete only if nothing lies beyond.
pub(super) fn complete(
    tile: &TilePoints,
    p: DVec3,
    nbr: &[Neighbour],
    want: usize,
) -> Result<(), f64> {
    let reach = match nbr.last() {
        Some(last) if nbr.len() == want => last.dist2.sqrt(),
        _ => f64::INFINITY,
    };
    let room = tile.room(p);
    if reach > room {
        Err(reach - room)
    } else {
        Ok(())
    }
}

fn plane_value(s: &Samples, i: u32, p: DVec3) -> f64 {
    (p - s.points[i as usize]).dot(s.normals[i as usize])
}

/// Sample `i`'s plane value at `p` if its projection lands on data.
fn try_plane(
    s: &Samples,
    tile: &TilePoints,
    p: DVec3,
    i: u32,
    limit: f64,
    nbr: &mut Vec<Neighbour>,
) -> Result<Option<f64>, f64> {
    let f = plane_value(s, i, p);
    let z = p - f * s.normals[i as usize];
    // The sample's own distance to its projection usually settles it: the
    // nearest sample to `z` is no farther (same distance formula as the
    // index), so the query below would say the same.
    if dist2(s.points[i as usize], z).sqrt() < limit {
        return Ok(Some(f));
    }
    let on_data = projection_on_data(s, tile, z, i, limit, nbr)?;
    Ok(on_data.then_some(f))
}

/// Whether some sample lies within `limit` of `z`; `Err` with the shortfall
/// when the loaded region cannot tell.
pub(super) fn projection_on_data(
    s: &Samples,
    tile: &TilePoints,
    z: DVec3,
    sample: u32,
    limit: f64,
    nbr: &mut Vec<Neighbour>,
) -> Result<bool, f64> {
    // `z` is the projection of `sample` onto its own plane: that sample is
    // close, a good start.
    nearest(s, z, Some(sample), nbr);
    match nbr.first() {
        Some(m) if m.dist2.sqrt() < limit => Ok(true),
        // Nothing loaded within the limit: true only if nothing unloaded is.
        _ if tile.room(z) >= limit => Ok(false),
        _ => Err(limit - tile.room(z)),
    }
}

/// The sample nearest to `q` into `nbr`, the search started from sample
/// `hint` when given (any hint gives the same answer).
fn nearest(s: &Samples, q: DVec3, hint: Option<u32>, nbr: &mut Vec<Neighbour>) {
    match hint.and_then(|h| Some((h, *s.points.get(h as usize)?))) {
        Some(h) => s.index.nearest_from(q, h, nbr),
        None => s.index.knn(q, 1, None, nbr),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Samples on the plane z = 0 at integer x, y in [-10, 10], normals +z
    /// except those listed in `flipped`, all loaded.
    fn plane_samples(flipped: &[DVec3]) -> (Vec<DVec3>, Vec<DVec3>, Vec<u64>, TilePoints) {
        let points: Vec<DVec3> = (-10..=10)
            .flat_map(|y| (-10..=10).map(move |x| DVec3::new(x as f64, y as f64, 0.0)))
            .collect();
        let normals = points
            .iter()
            .map(|p| {
                if flipped.contains(p) {
                    -DVec3::Z
                } else {
                    DVec3::Z
                }
            })
            .collect();
        let ids = (0..points.len() as u64).collect();
        let tile = TilePoints::whole(Vec::new());
        (points, normals, ids, tile)
    }

    fn value(
        points: &[DVec3],
        normals: &[DVec3],
        ids: &[u64],
        tile: &TilePoints,
        p: DVec3,
        limit: f64,
    ) -> f64 {
        let index = GridIndex::with_cell(points, ids, 1.5).expect("index");
        let s = Samples {
            points,
            normals,
            index: &index,
        };
        match signed_distance(&s, tile, p, limit, &mut Vec::new()) {
            Corner::Value(Some(f)) => f,
            other => panic!("{other:?} at {p}"),
        }
    }

    #[test]
    fn averaged_planes_reproduce_a_plane() {
        let (points, normals, ids, tile) = plane_samples(&[]);
        for p in [DVec3::new(0.3, 0.2, 0.7), DVec3::new(-2.5, 4.0, -1.25)] {
            let f = value(&points, &normals, &ids, &tile, p, f64::INFINITY);
            assert!((f - p.z).abs() < 1e-12, "{f} at {p}");
        }
    }

    #[test]
    fn one_flipped_sample_flips_the_nearest_plane_but_not_the_average() {
        let bad = DVec3::ZERO;
        let (points, normals, ids, tile) = plane_samples(&[bad]);
        let p = DVec3::new(0.1, -0.1, 0.5);
        // Paper 1's value, nearest plane only (a finite limit the
        // projection meets): the wrong sign above the flipped sample.
        assert!(value(&points, &normals, &ids, &tile, p, 10.0) < 0.0);
        let f = value(&points, &normals, &ids, &tile, p, f64::INFINITY);
        assert!(f > 0.3, "averaged value {f}");
    }
}
