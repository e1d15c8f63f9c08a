//! Section 2's feature points kept only where the curvature peaks across
//! the line (deviation from paper 5, named).
//!
//! Why: the paper's feature points are those with `|k_i| > alpha`. On a
//! sharp crease that is a narrow band, but on a smooth crest `k_i` stays
//! above any threshold for many spacings either side, and on a surface of
//! constant curvature (a sphere, a cylinder, a torus along its tube) the
//! threshold is met by the noise alone wherever `alpha` falls below the
//! curvature: a corrugated sheet gave a band of zigzag segments several
//! spacings wide, a torus 122 polylines over its whole surface. Ridge
//! lines are where the principal curvature is extreme across the line
//! (Ohtake, Belyaev and Seidel 2004, "Ridge-valley lines on meshes via
//! implicit surface fitting": `d k_max / d t_max = 0` with a sign test on
//! its derivative; paper 5's own reference \[10\] traces them the same way
//! on meshes). On points that is a test of the curvature field itself:
//! `k_i` of the neighbours, as a height over the tangent plane, fitted
//! with paper 5's quadratic (formula (3)); its Hessian's most negative
//! eigenvector is the direction across the crest (no principal direction
//! is needed, so a crease, whose quadric rounds the edge off, is tested
//! the same way). A point stays a feature point when
//! - near (the fit radius `r`): the fitted field is concave across, and
//!   its maximum across lies within `band` of the point (1.5 `d`, about
//!   3 sp each side: a band that narrow, not one of several spacings);
//! - wide (`2.5 r`): the field drops across the crest by at least
//!   `contrast` over the wide radius. `contrast` is a multiple of the
//!   curvature the fit noise alone makes, `sigma / r^2` (`sigma` the
//!   median fit residual, as `alpha`'s floor): noise in `k_i` is smooth
//!   over `r` (neighbours share most of their points), so a bump of noise
//!   looks like a crest near, and only the wider fit tells them apart.
//!
//! Measured (100k points, noise 0.1 sp, the quantiles of the wide drop in
//! units of `sigma / r^2` among points that pass the near test): a torus
//! 1.7 median, 6.1 at the 99th percentile, 7.6 at most; a sphere 1.8, 5.1,
//! 8.5; a corrugated sheet (crest amplitude a quarter of the wavelength)
//! on its crests 86 at the 10th percentile; with an eighth, noise 0.5 sp,
//! 14 at the 10th percentile. Hence [`DEFAULT_CONTRAST`].
//!
//! For valleys the field is `-k_i`. Every value read lies within the wide
//! radius of the point, in the ball's canonical order, so a tile decides
//! exactly as the whole cloud does when that ball is loaded (`kernel.rs`).

use super::quadric::fit_quadratic;
use crate::spatial::{BallGrid, Neighbour};
use glam::{DVec2, DVec3};

/// The wide drop a crest must reach, in units of `sigma / r^2` (see the
/// module doc for the measurements it sits between).
pub const DEFAULT_CONTRAST: f64 = 9.0;
/// The wide fit's radius, in curvature fit radii.
pub const WIDE_RADII: f64 = 2.5;
/// How far the fitted maximum may lie from the point, in mean spacings `d`.
/// The near fit's maximum scatters by about a spacing with the noise, and
/// the enhancement needs a few points across the line: at 0.5 `d` the
/// wavy sheet's lines broke into 98 polylines (22 true lines) with recall
/// 84 %, at 1.0 `d` 37 polylines, at 1.5 `d` 23 (recall 99 %, precision
/// 99 %); the crease figures are as good as without the test or better.
pub const BAND_SPACINGS: f64 = 1.5;

/// The test's sizes, absolute.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PeakTest {
    /// Near fit radius (the curvature fit radius `r`).
    pub near: f64,
    /// Wide fit radius.
    pub wide: f64,
    /// Largest distance of the fitted maximum from the point.
    pub band: f64,
    /// Smallest drop of the field across the crest over `wide` (1 / length).
    pub contrast: f64,
}

/// Whether the field `value` (a point's `k_i`, signed so that the line is
/// a maximum; `None` where unknown) peaks across a line through `p`, of
/// oriented normal `n`. `grid` indexes the points `value` is over, with
/// cells of at least `test.wide / 8`; `found` is scratch.
pub fn on_crest(
    p: DVec3,
    n: DVec3,
    grid: &BallGrid,
    value: &impl Fn(usize) -> Option<f64>,
    test: &PeakTest,
    found: &mut Vec<Neighbour>,
) -> bool {
    let (u, v) = n.any_orthonormal_pair();
    grid.within(p, test.wide, None, found);
    let local = |nb: &Neighbour| {
        let d = grid.points()[nb.index as usize] - p;
        value(nb.index as usize).map(|k| DVec3::new(d.dot(u), d.dot(v), k))
    };
    let near2 = test.near * test.near;
    let wide = found.iter().filter_map(local);
    let near = found
        .iter()
        .filter(|nb| nb.dist2 <= near2)
        .filter_map(local);
    let (Some(wide), Some(near)) = (across(wide), across(near)) else {
        return false;
    };
    let drop = -wide.curvature * test.wide * test.wide / 2.0;
    drop >= test.contrast && near.curvature < 0.0 && near.offset.abs() <= test.band
}

/// The fitted field across its line: the second derivative along the
/// most concave direction, and where along it the maximum lies.
struct Across {
    curvature: f64,
    offset: f64,
}

fn across<I: Iterator<Item = DVec3> + Clone>(samples: I) -> Option<Across> {
    let [_, b, c, d, e, f] = fit_quadratic(samples).ok()?;
    // Hessian [[2e, d], [d, 2f]]: its smaller eigenvalue and eigenvector.
    let (h11, h12, h22) = (2.0 * e, d, 2.0 * f);
    let mean = 0.5 * (h11 + h22);
    let radius = (0.25 * (h11 - h22) * (h11 - h22) + h12 * h12).sqrt();
    let lambda = mean - radius;
    let dir = if h12.abs() > 1e-300 {
        DVec2::new(lambda - h22, h12).normalize()
    } else if h11 <= h22 {
        DVec2::X
    } else {
        DVec2::Y
    };
    let slope = DVec2::new(b, c).dot(dir);
    let offset = if lambda < 0.0 {
        -slope / lambda
    } else {
        f64::INFINITY
    };
    Some(Across {
        curvature: lambda,
        offset,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn test_sizes() -> PeakTest {
        PeakTest {
            near: 1.0,
            wide: 2.5,
            band: 0.2,
            contrast: 0.5,
        }
    }

    /// A grid of points on the plane z = 0, the field given per point.
    fn plane(field: impl Fn(f64, f64) -> f64) -> (Vec<DVec3>, Vec<u64>, Vec<f64>) {
        let mut pts = Vec::new();
        for i in -40..=40 {
            for j in -40..=40 {
                pts.push(DVec3::new(i as f64 * 0.1, j as f64 * 0.1, 0.0));
            }
        }
        let ids = (0..pts.len() as u64).collect();
        let vals = pts.iter().map(|p| field(p.x, p.y)).collect();
        (pts, ids, vals)
    }

    fn crest_at(field: impl Fn(f64, f64) -> f64, p: DVec3) -> bool {
        let (pts, ids, vals) = plane(field);
        let grid = BallGrid::new(&pts, &ids, 1.0).expect("grid");
        let value = |i: usize| Some(vals[i]);
        let mut found = Vec::new();
        on_crest(p, DVec3::Z, &grid, &value, &test_sizes(), &mut found)
    }

    /// A crest along y at x = 0.3: points on it pass, points 0.5 beside
    /// it do not (the maximum is beyond the band), whatever y.
    #[test]
    fn a_crest_passes_on_it_and_not_beside_it() {
        let crest = |x: f64, _y: f64| 5.0 - (x - 0.3) * (x - 0.3);
        for y in [-1.0, 0.0, 1.3] {
            assert!(crest_at(crest, DVec3::new(0.3, y, 0.0)));
            assert!(!crest_at(crest, DVec3::new(0.8, y, 0.0)));
            assert!(!crest_at(crest, DVec3::new(-0.2, y, 0.0)));
        }
    }

    /// A constant field, a tilted plane and a trough have no crest; a
    /// crest too shallow for the contrast is dropped.
    #[test]
    fn no_crest_where_the_field_does_not_peak() {
        let origin = DVec3::ZERO;
        assert!(!crest_at(|_, _| 3.0, origin));
        assert!(!crest_at(|x, y| 3.0 + x - 0.5 * y, origin));
        assert!(!crest_at(|x, _| 3.0 + x * x, origin));
        // Drop over the wide radius: 0.1 * 2.5^2 = 0.625 >= 0.5; 0.05: 0.31.
        assert!(crest_at(|x, _| 3.0 - 0.1 * x * x, origin));
        assert!(!crest_at(|x, _| 3.0 - 0.05 * x * x, origin));
    }

    /// The across direction comes from the field, not from the axes: a
    /// crest along a diagonal is found on it.
    #[test]
    fn a_diagonal_crest_is_found_on_it() {
        let diag = |x: f64, y: f64| 2.0 - (x - y) * (x - y);
        assert!(crest_at(diag, DVec3::new(0.5, 0.5, 0.0)));
        assert!(!crest_at(diag, DVec3::new(0.5, -0.5, 0.0)));
    }
}
