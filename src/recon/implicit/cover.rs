//! Whether a point on the surface lies among the samples or beyond the
//! data's edge: the open boundary of the MLS field (issue 19).
//!
//! A projection is *covered* when samples surround it in its tangent plane:
//! seen from it, the directions to nearby samples leave no empty half-turn
//! (it lies inside their convex hull). Beyond an open boundary a half-plane
//! holds no sample however far one looks; inside a random void of the
//! sampling, samples stand all round it a few spacings away.
//!
//! Deviation from paper 1 section 2.5, which defines a corner where its
//! projection lies within `rho + delta` of a sample: `rho` is the cloud's
//! *largest* nearest-neighbour distance (8 spacings on the test terrain, set
//! by its sparsest sample), so the mesh ran that far past every edge of the
//! scan (the terrain's Hausdorff distance, 7.4 spacings). Paper 1's test is
//! kept as the outer bound; this one trims the boundary to the samples'
//! local hull, whatever the density. A test of the nearest sample's
//! distance against a *local* spacing cannot do it: in the middle of a
//! random void the nearest sample is as far, relative to the spacing, as it
//! is a few spacings past the edge.

use super::sdf::{complete, Samples};
use crate::geom::pseudo_angle;
use crate::spatial::{KnnIndex, Neighbour};
use crate::tiling::TilePoints;
use glam::{DVec2, DVec3};

/// Samples round a projection whose directions are checked when the field's
/// own neighbours do not surround it. About 8 spacings' reach: random voids
/// of the sampling span 2 to 4 spacings (the largest empty circle among
/// N uniform samples has radius `2 sqrt(ln N / pi)` spacings: 3.9 at 200k,
/// 4.5 at 10M), so samples stand all round their middle within it.
pub const COVER_NEIGHBOURS: usize = 48;

/// Whether `z`, a point on the surface with normal `n`, is covered by the
/// first [`COVER_NEIGHBOURS`] samples in `nbr` (any set, e.g. the field's
/// neighbours of a nearby corner): they surround it in the plane through
/// `z` normal to `n`. A sample at `z` itself covers it.
///
/// Most corners lie well inside the data: when samples stand in all four
/// open quadrants round `z`, no half-plane through it holds them all
/// (every closed half-plane through `z` misses one open quadrant), which
/// settles it. Otherwise the directions are ordered by pseudo-angle and
/// each step between consecutive ones tested by its cross product. This
/// runs at every defined corner (9 million on the 1M dragon); `atan2` and
/// a sort at each cost a fifth of the reconstruction.
pub fn surrounds(points: &[DVec3], z: DVec3, n: DVec3, nbr: &[Neighbour]) -> bool {
    let n = n.normalize_or_zero();
    if n == DVec3::ZERO {
        return false;
    }
    let (u, v) = n.any_orthonormal_pair();
    let nbr = &nbr[..nbr.len().min(COVER_NEIGHBOURS)];
    let dir = |m: &Neighbour| {
        let d = points[m.index as usize] - z;
        DVec2::new(d.dot(u), d.dot(v))
    };
    let mut quadrants = 0u8;
    for w in nbr.iter().map(dir) {
        if w == DVec2::ZERO {
            return true;
        }
        if w.x != 0.0 && w.y != 0.0 {
            quadrants |= 1 << (u8::from(w.x < 0.0) + 2 * u8::from(w.y < 0.0));
            if quadrants == 0b1111 {
                return true;
            }
        }
    }
    // Fewer than three directions leave a half-turn empty.
    if nbr.len() < 3 {
        return false;
    }
    let mut dirs: Vec<(f64, DVec2)> = nbr.iter().map(dir).map(|w| (pseudo_angle(w), w)).collect();
    dirs.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
    let within = dirs
        .windows(2)
        .all(|w| w[0].1.perp_dot(w[1].1) > 0.0 || same_way(w[0].1, w[1].1));
    // The step from the last round to the first: strictly less than a
    // half-turn (equal directions there mean they all point one way).
    within && dirs[dirs.len() - 1].1.perp_dot(dirs[0].1) > 0.0
}

fn same_way(a: DVec2, b: DVec2) -> bool {
    a.perp_dot(b) == 0.0 && a.dot(b) > 0.0
}

/// Whether `z` is covered, asking its [`COVER_NEIGHBOURS`] nearest samples;
/// `Err` with the shortfall when the loaded region cannot tell.
pub fn covered(
    s: &Samples,
    tile: &TilePoints,
    z: DVec3,
    n: DVec3,
    nbr: &mut Vec<Neighbour>,
) -> Result<bool, f64> {
    s.index.knn(z, COVER_NEIGHBOURS, None, nbr);
    complete(tile, z, nbr, COVER_NEIGHBOURS)?;
    Ok(surrounds(s.points, z, n, nbr))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::{PI, TAU};

    fn neighbours(points: &[DVec3]) -> Vec<Neighbour> {
        (0..points.len() as u32)
            .map(|index| Neighbour { index, dist2: 0.0 })
            .collect()
    }

    fn ring(count: usize, from: f64, to: f64) -> Vec<DVec3> {
        (0..count)
            .map(|i| {
                let a = from + (to - from) * i as f64 / (count - 1) as f64;
                DVec3::new(a.cos(), a.sin(), 0.3 * (i % 3) as f64)
            })
            .collect()
    }

    fn samples_surround(points: &[DVec3], z: DVec3) -> bool {
        surrounds(points, z, DVec3::Z, &neighbours(points))
    }

    #[test]
    fn a_full_ring_covers_its_middle_and_not_beyond() {
        let points = ring(12, 0.0, TAU * 11.0 / 12.0);
        assert!(samples_surround(&points, DVec3::ZERO));
        assert!(samples_surround(&points, DVec3::new(0.5, 0.2, 0.0)));
        assert!(!samples_surround(&points, DVec3::new(1.5, 0.0, 0.0)));
    }

    #[test]
    fn a_half_ring_leaves_its_open_side_uncovered() {
        // Directions from 0 to 0.9 pi: the gap from 0.9 pi round to 2 pi
        // is wider than a half-turn.
        let points = ring(10, 0.0, 0.9 * PI);
        assert!(!samples_surround(&points, DVec3::ZERO));
        // Just past a half-turn the other way, the gap closes below pi.
        let points = ring(10, 0.0, 1.1 * PI);
        assert!(samples_surround(&points, DVec3::ZERO));
    }

    #[test]
    fn no_samples_cover_nothing_and_a_sample_on_the_point_covers_it() {
        assert!(!samples_surround(&[], DVec3::ZERO));
        assert!(samples_surround(&[DVec3::ZERO], DVec3::ZERO));
    }

    #[test]
    fn directions_all_one_way_cover_nothing() {
        let points = [DVec3::X, 2.0 * DVec3::X, 3.0 * DVec3::X];
        assert!(!samples_surround(&points, DVec3::ZERO));
        // Two opposite directions leave exactly a half-turn on each side.
        let points = [DVec3::X, -DVec3::X, 2.0 * DVec3::X];
        assert!(!samples_surround(&points, DVec3::ZERO));
    }
}
