//! The local quadratic of paper 5 section 2 (formulas (1)-(3)): a
//! neighbourhood's PCA frame `(o, u, v, n)` with `n` oriented by the
//! point's normal, the least-squares height function
//! `g(u, v) = a + b u + c v + d uv + e u^2 + f v^2` over it, and its MLS
//! residual (section 6).
//!
//! The 6x6 normal equations are solved by Cholesky on coordinates scaled by
//! the neighbourhood's radius, so their entries are O(1) whatever the units
//! (unscaled, `u^4` terms of a 1e-4 m neighbourhood are 1e-16 and the
//! paper's Gaussian elimination would work on rounding noise). A pivot that
//! keeps less than [`PIVOT_TOLERANCE`] of its column's diagonal means the
//! column is (nearly) a combination of the earlier ones: the neighbourhood
//! does not span the plane (points on a line or a conic in `(u, v)`), so
//! `g` is not determined and the point is flagged, never given a made-up
//! value. A flat neighbourhood is not a problem: its points spread in
//! `(u, v)` and the fit returns `d = e = f = 0` to rounding.

use super::{FLAG_DEGENERATE, FLAG_ILL_CONDITIONED, FLAG_SPARSE};
use crate::normals::eigen::sym3_eigen;
use glam::DVec3;

/// Fewest points (the point itself included) a quadratic is fitted to: one
/// more than its six unknowns, so the residual means something.
pub const MIN_FIT_POINTS: usize = 7;
/// A Cholesky pivot below this fraction of its original diagonal flags the
/// fit as ill-conditioned (the squared sine of the angle between that
/// column and the span of the earlier ones).
pub const PIVOT_TOLERANCE: f64 = 1e-9;
/// PCA eigenvalue gap below which the frame is undetermined (as the
/// normals' colinear test).
const FRAME_TOLERANCE: f64 = 1e-10;

/// An orthonormal frame at a neighbourhood's centroid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    pub origin: DVec3,
    /// Direction of largest spread.
    pub u: DVec3,
    pub v: DVec3,
    /// Oriented normal (`n = u x v`).
    pub n: DVec3,
}

impl Frame {
    /// `(u, v, height)` coordinates of `p`.
    pub fn local(&self, p: DVec3) -> DVec3 {
        let d = p - self.origin;
        DVec3::new(d.dot(self.u), d.dot(self.v), d.dot(self.n))
    }

    /// The point with local coordinates `(x, y, z)`.
    pub fn global(&self, x: f64, y: f64, z: f64) -> DVec3 {
        self.origin + self.u * x + self.v * y + self.n * z
    }
}

/// A fitted height function in its frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Quadric {
    pub frame: Frame,
    /// `[a, b, c, d, e, f]` of `g(u, v) = a + b u + c v + d uv + e u^2 + f v^2`.
    pub coef: [f64; 6],
    /// Root mean square of `E_j = z_j - g(u_j, v_j)` over the neighbourhood.
    pub rms: f64,
    /// Largest `|E_j|`.
    pub max_error: f64,
}

/// Curvatures at one point of a fitted quadric. Signs: convex (the surface
/// bends away from the outward normal) is positive; see [`Quadric::curvature_at`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Curvature {
    pub k1: f64,
    pub k2: f64,
    pub mean: f64,
    pub gauss: f64,
}

impl Quadric {
    /// `g(x, y)`.
    pub fn height(&self, x: f64, y: f64) -> f64 {
        let [a, b, c, d, e, f] = self.coef;
        a + b * x + c * y + d * x * y + e * x * x + f * y * y
    }

    /// The surface point over `(x, y)` (paper: `o + (x, y, g(x, y))`).
    pub fn lift(&self, x: f64, y: f64) -> DVec3 {
        self.frame.global(x, y, self.height(x, y))
    }

    /// Gaussian, mean and principal curvatures of the graph of `g` over
    /// `(x, y)`, by the paper's formulas for `K`, `H` and `k1,2 = H +-
    /// sqrt(H^2 - K)` (the `g_v` in the paper's text reads `c + dv + 2fv`, a
    /// typo for `c + du + 2fv`, which its `F`, `G` and `k_h` use).
    ///
    /// Deviation: with the outward `Z` the paper asks for, its formulas make
    /// a convex point negative (a sphere of radius R has `e = f = -1/2R`, so
    /// `H = -1/R`), while its text calls convex points ridges with `k > 0`.
    /// We follow the text: `H`, `k1`, `k2` are negated (curvature with respect
    /// to the inward normal); `K` does not depend on the side.
    pub fn curvature_at(&self, x: f64, y: f64) -> Curvature {
        let [_, b, c, d, e, f] = self.coef;
        let gu = b + d * y + 2.0 * e * x;
        let gv = c + d * x + 2.0 * f * y;
        let w2 = 1.0 + gu * gu + gv * gv;
        let w = w2.sqrt();
        let gauss = (4.0 * e * f - d * d) / (w2 * w2);
        let mean = -(e + f + e * gv * gv + f * gu * gu - d * gu * gv) / (w2 * w);
        let root = (mean * mean - gauss).max(0.0).sqrt();
        Curvature {
            k1: mean + root,
            k2: mean - root,
            mean,
            gauss,
        }
    }
}

/// Why a neighbourhood has no quadric: a [`super`] flag bit.
pub type FitFlag = u8;

/// PCA frame of `pts` (the point itself first), its normal turned toward
/// `toward` (the point's oriented normal).
pub fn pca_frame(pts: &[DVec3], toward: DVec3) -> Result<Frame, FitFlag> {
    let Some(&anchor) = pts.first() else {
        return Err(FLAG_SPARSE);
    };
    let n = pts.len() as f64;
    let offset = pts.iter().fold(DVec3::ZERO, |s, p| s + (*p - anchor)) / n;
    let mut m = [[0.0f64; 3]; 3];
    for p in pts {
        let d = (*p - anchor) - offset;
        for (r, row) in m.iter_mut().enumerate() {
            for (c, cell) in row.iter_mut().enumerate() {
                *cell += d[r] * d[c];
            }
        }
    }
    let (vals, vecs) = sym3_eigen(m);
    if vals[2].is_nan() || vals[2] <= 0.0 || vals[1] - vals[0] <= FRAME_TOLERANCE * vals[2] {
        return Err(FLAG_DEGENERATE);
    }
    let mut normal = vecs[0].normalize();
    if normal.dot(toward) < 0.0 {
        normal = -normal;
    }
    let u = (vecs[2] - normal * vecs[2].dot(normal)).normalize();
    Ok(Frame {
        origin: anchor + offset,
        u,
        v: normal.cross(u),
        n: normal,
    })
}

/// Fits paper 5's quadratic (formula (3)) to `pts` in `frame`. The local
/// coordinates are recomputed in each pass rather than stored: three dot
/// products cost less than an allocation per fit.
pub fn fit_quadric(pts: &[DVec3], frame: Frame) -> Result<Quadric, FitFlag> {
    let coef = fit_quadratic(pts.iter().map(|p| frame.local(*p)))?;
    let mut q = Quadric {
        frame,
        coef,
        rms: 0.0,
        max_error: 0.0,
    };
    let mut sum2 = 0.0;
    for p in pts {
        let l = frame.local(*p);
        let err = (l.z - q.height(l.x, l.y)).abs();
        sum2 += err * err;
        q.max_error = q.max_error.max(err);
    }
    q.rms = (sum2 / pts.len() as f64).sqrt();
    Ok(q)
}

/// The least-squares `z = g(x, y)` (formula (3)'s basis) over samples
/// `(x, y, z)` in a local frame, solved on coordinates scaled by the
/// samples' radius (see the module doc). `z` may be any field over the
/// plane (`peak.rs` fits the curvature itself).
pub(crate) fn fit_quadratic<I>(samples: I) -> Result<[f64; 6], FitFlag>
where
    I: Iterator<Item = DVec3> + Clone,
{
    let (count, reach2) = samples.clone().fold((0usize, 0.0f64), |(n, r), l| {
        (n + 1, r.max(l.x * l.x + l.y * l.y))
    });
    if count < MIN_FIT_POINTS {
        return Err(FLAG_SPARSE);
    }
    let scale = reach2.sqrt();
    if !(scale > 0.0 && scale.is_finite()) {
        return Err(FLAG_DEGENERATE);
    }
    let inv = 1.0 / scale;
    let mut ata = [[0.0f64; 6]; 6];
    let mut atz = [0.0f64; 6];
    for l in samples {
        let row = basis(l.x * inv, l.y * inv);
        let z = l.z * inv;
        for r in 0..6 {
            atz[r] += row[r] * z;
            for c in 0..=r {
                ata[r][c] += row[r] * row[c];
            }
        }
    }
    let s = solve_spd6(ata, atz).ok_or(FLAG_ILL_CONDITIONED)?;
    // Back from scaled coordinates: z = scale * g~(u / scale, v / scale).
    Ok([s[0] * scale, s[1], s[2], s[3] * inv, s[4] * inv, s[5] * inv])
}

fn basis(x: f64, y: f64) -> [f64; 6] {
    [1.0, x, y, x * y, x * x, y * y]
}

/// Solves `A s = b` for symmetric positive definite `A` (lower triangle
/// given) by Cholesky; `None` when a pivot falls below
/// [`PIVOT_TOLERANCE`] of its diagonal (rank deficient or nearly so).
pub(crate) fn solve_spd6(mut a: [[f64; 6]; 6], b: [f64; 6]) -> Option<[f64; 6]> {
    let dot = |x: &[f64], y: &[f64]| x.iter().zip(y).map(|(p, q)| p * q).sum::<f64>();
    for k in 0..6 {
        let diag = a[k][k];
        let pivot = diag - dot(&a[k][..k], &a[k][..k]);
        // Also catches NaN.
        if pivot.is_nan() || pivot <= PIVOT_TOLERANCE * diag {
            return None;
        }
        let l = pivot.sqrt();
        a[k][k] = l;
        for i in k + 1..6 {
            a[i][k] = (a[i][k] - dot(&a[i][..k], &a[k][..k])) / l;
        }
    }
    // Forward (L y = b), then back (L^T x = y) substitution.
    let mut y = [0.0f64; 6];
    for i in 0..6 {
        y[i] = (b[i] - dot(&a[i][..i], &y[..i])) / a[i][i];
    }
    let mut x = [0.0f64; 6];
    for i in (0..6).rev() {
        let above: f64 = (i + 1..6).map(|j| a[j][i] * x[j]).sum();
        x[i] = (y[i] - above) / a[i][i];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    fn disc(rng: &mut Rng, n: usize, r: f64) -> Vec<(f64, f64)> {
        (0..n)
            .map(|_| {
                let (c, s) = rng.unit_circle();
                let t = r * rng.uniform().sqrt();
                (c * t, s * t)
            })
            .collect()
    }

    #[test]
    fn recovers_an_exact_quadratic() {
        let mut rng = Rng::new(3);
        let want = [0.01, 0.2, -0.1, 0.7, 1.5, -0.4];
        let g = |x: f64, y: f64| {
            let [a, b, c, d, e, f] = want;
            a + b * x + c * y + d * x * y + e * x * x + f * y * y
        };
        let frame = Frame {
            origin: DVec3::ZERO,
            u: DVec3::X,
            v: DVec3::Y,
            n: DVec3::Z,
        };
        let pts: Vec<DVec3> = disc(&mut rng, 30, 1e-3)
            .into_iter()
            .map(|(x, y)| DVec3::new(x, y, g(x, y)))
            .collect();
        let q = fit_quadric(&pts, frame).unwrap();
        for (got, want) in q.coef.iter().zip(want) {
            assert!(
                (got - want).abs() < 1e-6 * want.abs().max(1.0),
                "{got} vs {want}"
            );
        }
        assert!(q.rms < 1e-15, "{}", q.rms);
    }

    #[test]
    fn collinear_uv_is_flagged_not_solved() {
        let frame = Frame {
            origin: DVec3::ZERO,
            u: DVec3::X,
            v: DVec3::Y,
            n: DVec3::Z,
        };
        let pts: Vec<DVec3> = (0..20)
            .map(|i| DVec3::new(i as f64 * 0.1, 0.0, 0.01 * i as f64))
            .collect();
        assert_eq!(fit_quadric(&pts, frame), Err(FLAG_ILL_CONDITIONED));
        assert_eq!(fit_quadric(&pts[..5], frame), Err(FLAG_SPARSE));
    }

    #[test]
    fn sphere_cap_is_convex_positive() {
        let mut rng = Rng::new(9);
        let r = 2.0;
        let pts: Vec<DVec3> = std::iter::once((0.0, 0.0))
            .chain(disc(&mut rng, 40, 0.3))
            .map(|(x, y)| DVec3::new(x, y, (r * r - x * x - y * y).sqrt()))
            .collect();
        let frame = pca_frame(&pts, DVec3::Z).unwrap();
        let q = fit_quadric(&pts, frame).unwrap();
        let l = frame.local(pts[0]);
        let k = q.curvature_at(l.x, l.y);
        assert!(
            (k.k1 - 0.5).abs() < 0.01 && (k.k2 - 0.5).abs() < 0.01,
            "{k:?}"
        );
        assert!((k.gauss - 0.25).abs() < 0.01, "{k:?}");
        // Seen from inside (normal toward the centre), the same cap is concave.
        let inside = pca_frame(&pts, -DVec3::Z).unwrap();
        let k = fit_quadric(&pts, inside).unwrap().curvature_at(0.0, 0.0);
        assert!(k.mean < -0.49, "{k:?}");
    }
}
