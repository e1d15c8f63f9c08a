//! Eigen-decomposition of symmetric 3x3 matrices, for the PCA tangent planes
//! of paper 1 section 2.3 (the smallest eigenpair of the covariance).
//!
//! Deviation from the paper: it suggests inverse iteration for the smallest
//! eigenpair alone; we want all three eigenvalues (surface variation, the
//! colinear test of `pca.rs`), so we decompose fully. The normals stage does
//! this once per point: cyclic Jacobi (kept as [`sym3_eigen_jacobi`]) took
//! ~1570 instructions per call and 7 % of `scanmesh normals`; the analytic
//! method below takes ~490 (callgrind, realistic PCA covariances).
//!
//! Method: one cubic root and one 2x2 rotation (after D. Eberly, "A Robust
//! Eigensolver for 3x3 Symmetric Matrices", Geometric Tools, 2014).
//! 1. Shift and normalise: `D = (A - q I) / s` with `q = tr A / 3` and `s`
//!    chosen so that the squared entries of `D` sum to 6. Its eigenvalues are
//!    then the roots of `t^3 - 3 t - det D = 0`, all in [-2, 2], whatever the
//!    scale of `A` (covariances of centred points are O(spacing^2): 1e-30
//!    and 1e30 give the same `D`).
//! 2. The *isolated* eigenvalue only: the largest if `det D >= 0`, else the
//!    smallest. It is at least sqrt(3) from both others, a simple and
//!    well-conditioned root: a cubic fit of the trigonometric solution
//!    `2 cos(acos(|det D| / 2) / 3)` (error 7e-5) and two Newton steps give
//!    it to rounding, with no acos/cos calls.
//! 3. Its eigenvector: the largest cross product of two rows of `D - t I`
//!    (rank exactly 2, since the root is simple and far from the others).
//! 4. The other two pairs: `D` restricted to the plane orthogonal to that
//!    vector, a 2x2 block diagonalised by one Jacobi rotation.
//!
//! Why not the textbook analytic solver (all three roots by the
//! trigonometric formula, every eigenvector from cross products)? Near a
//! repeated eigenvalue `acos` is taken where its slope is infinite, so the
//! clustered roots lose half their digits (1e-8 of the scale), and the cross
//! products of rows of a rank-1 matrix are noise: exactly the flat, colinear
//! and isotropic neighbourhoods of quantised LAS data (PITFALLS.md, Open3D
//! #880). Here no clustered eigenvalue comes from the cubic and no clustered
//! eigenvector from a cross product; a cluster is split by an orthogonal
//! rotation, which cannot fail (for a repeated pair every angle is right).
//! So the errors are Jacobi's, absolute `O(eps |A|)` in eigenvalues and
//! `O(eps |A| / gap)` in eigenvectors, whatever the gaps, and the fallback
//! to Jacobi on small gaps that one might expect is not needed: the tests
//! hold this solver to Jacobi (1e-12 |A|) on exactly and nearly repeated
//! spectra.
//!
//! Fallback: diagonal matrices (the zero matrix included) are sorted as they
//! are, exactly. Matrices whose shifted squared entries are not finite (NaN,
//! inf) or outside [1e-290, 1e290] (spreads beyond ~1e145, where the
//! normalisation would overflow or lose bits to subnormals) go to Jacobi,
//! which prescales by a power of two and bounds its sweeps.

mod jacobi;
#[cfg(test)]
mod tests;

use glam::DVec3;

use jacobi::rotation_tangent;
pub use jacobi::sym3_eigen_jacobi;

/// Below this squared spread the normalisation of the shifted matrix would
/// lose bits to subnormals; Jacobi takes such matrices (far from any
/// covariance of real coordinates).
const MIN_SQUARES: f64 = 1e-290;
/// Above this squared spread the squares could overflow; Jacobi again.
const MAX_SQUARES: f64 = 1e290;

/// Eigenvalues in ascending order and matching orthonormal eigenvectors of
/// the symmetric matrix `m` (its upper and lower triangles are averaged).
///
/// Each eigenvector has a canonical sign: its component of largest magnitude
/// is positive (on equal magnitudes, the first such axis). For exactly
/// repeated eigenvalues the basis of the eigenspace is whatever the solver
/// produced, deterministic for a given input. A zero matrix gives zero
/// eigenvalues and the unit axes. Non-finite input gives non-finite output,
/// never a panic or an endless loop.
pub fn sym3_eigen(m: [[f64; 3]; 3]) -> ([f64; 3], [DVec3; 3]) {
    analytic(&m).unwrap_or_else(|| sym3_eigen_jacobi(m))
}

/// Flips `v` so that its component of largest magnitude is positive (the
/// first axis among equal magnitudes).
pub(crate) fn canonical_sign(v: DVec3) -> DVec3 {
    let (x, y, z) = (v.x.abs(), v.y.abs(), v.z.abs());
    let largest = if y > x {
        if z > y {
            v.z
        } else {
            v.y
        }
    } else if z > x {
        v.z
    } else {
        v.x
    };
    if largest < 0.0 {
        -v
    } else {
        v
    }
}

/// The analytic solver; `None` sends `m` to Jacobi (non-finite entries, or
/// a spread outside [`MIN_SQUARES`, `MAX_SQUARES`]).
fn analytic(m: &[[f64; 3]; 3]) -> Option<([f64; 3], [DVec3; 3])> {
    let a = Sym::symmetrised(m);
    if a.xy == 0.0 && a.xz == 0.0 && a.yz == 0.0 {
        return Some(sorted_diagonal([a.xx, a.yy, a.zz]));
    }
    let q = (a.xx + a.yy + a.zz) / 3.0;
    let c = a.shifted(q);
    let squares = c.squared_norm();
    // Also false for NaN.
    if !(MIN_SQUARES..=MAX_SQUARES).contains(&squares) {
        return None;
    }
    let s = (squares / 6.0).sqrt();
    Some(solve_normalised(&c.scaled(1.0 / s), q, s))
}

/// The diagonal, ascending (ties by axis), with the unit axes.
fn sorted_diagonal(d: [f64; 3]) -> ([f64; 3], [DVec3; 3]) {
    let mut order = [0usize, 1, 2];
    order.sort_by(|&i, &j| d[i].total_cmp(&d[j]).then(i.cmp(&j)));
    (order.map(|i| d[i]), order.map(|i| DVec3::AXES[i]))
}

/// The eigen-decomposition of `A = q I + s D`, `D` traceless with squared
/// entries summing to 6: eigenvalues in [-2, 2], the isolated one (the
/// largest if `det D >= 0`, else the smallest) at least sqrt 3 from both
/// others.
fn solve_normalised(d: &Sym, q: f64, s: f64) -> ([f64; 3], [DVec3; 3]) {
    let det = d.determinant();
    let t = isolated_root(det.abs().min(2.0));
    let t = if det >= 0.0 { t } else { -t };
    let v = d.shifted(t).null_vector();
    let ((l0, v0), (l1, v1)) = split_complement(d, v);
    let value = |mu: f64| q + s * mu;
    let (v, v0, v1) = (canonical_sign(v), canonical_sign(v0), canonical_sign(v1));
    if det >= 0.0 {
        ([value(l0), value(l1), value(t)], [v0, v1, v])
    } else {
        ([value(t), value(l0), value(l1)], [v, v0, v1])
    }
}

/// The root of `t^3 - 3 t - b = 0` in [sqrt 3, 2], for `b` in [0, 2]: the
/// largest eigenvalue of a normalised `D` with `det D = b`.
fn isolated_root(b: f64) -> f64 {
    // Cubic Chebyshev fit of 2 cos(acos(r) / 3), r = b / 2 in [0, 1]; max
    // error 7.3e-5. Newton's error squares each step (f''/2f' <= 0.87 on
    // [sqrt 3, 2]): 4.6e-9, then 2e-17, below rounding.
    let r = 0.5 * b;
    let mut t = 1.732_123_75 + r * (0.330_808_4 + r * (-0.081_762_1 + r * 0.018_887_13));
    for _ in 0..2 {
        let t2 = t * t;
        t -= ((t2 - 3.0) * t - b) / (3.0 * t2 - 3.0);
    }
    t
}

/// The eigenpairs of `d` in the plane orthogonal to its unit eigenvector
/// `v`, ascending: one Jacobi rotation of the 2x2 block `d` has in the
/// basis `(u, w)` of that plane.
fn split_complement(d: &Sym, v: DVec3) -> ((f64, DVec3), (f64, DVec3)) {
    let (u, w) = orthonormal_complement(v);
    let (du, dw) = (d.mul(u), d.mul(w));
    let (m00, m01, m11) = (u.dot(du), w.dot(du), w.dot(dw));
    let (a, b) = if m01 == 0.0 {
        ((m00, u), (m11, w))
    } else {
        let t = rotation_tangent((m11 - m00) / (2.0 * m01));
        let c = 1.0 / (t * t + 1.0).sqrt();
        let s = t * c;
        (
            (m00 - t * m01, c * u - s * w),
            (m11 + t * m01, s * u + c * w),
        )
    };
    if a.0 <= b.0 {
        (a, b)
    } else {
        (b, a)
    }
}

/// Two unit vectors completing the unit `v` to an orthonormal basis; the
/// first drops the smaller of v's x, y components so its norm is >= 1/sqrt 2.
fn orthonormal_complement(v: DVec3) -> (DVec3, DVec3) {
    let u = if v.x.abs() > v.y.abs() {
        DVec3::new(-v.z, 0.0, v.x) * (1.0 / (v.x * v.x + v.z * v.z).sqrt())
    } else {
        DVec3::new(0.0, v.z, -v.y) * (1.0 / (v.y * v.y + v.z * v.z).sqrt())
    };
    (u, v.cross(u))
}

/// The six distinct entries of a symmetric 3x3 matrix.
#[derive(Clone, Copy, Debug)]
struct Sym {
    xx: f64,
    yy: f64,
    zz: f64,
    xy: f64,
    xz: f64,
    yz: f64,
}

impl Sym {
    /// The diagonal as it is (averaging it with itself could only overflow).
    fn symmetrised(m: &[[f64; 3]; 3]) -> Self {
        Self {
            xx: m[0][0],
            yy: m[1][1],
            zz: m[2][2],
            xy: 0.5 * (m[0][1] + m[1][0]),
            xz: 0.5 * (m[0][2] + m[2][0]),
            yz: 0.5 * (m[1][2] + m[2][1]),
        }
    }

    /// `self - t I`.
    fn shifted(&self, t: f64) -> Self {
        Self {
            xx: self.xx - t,
            yy: self.yy - t,
            zz: self.zz - t,
            ..*self
        }
    }

    fn scaled(&self, k: f64) -> Self {
        Self {
            xx: self.xx * k,
            yy: self.yy * k,
            zz: self.zz * k,
            xy: self.xy * k,
            xz: self.xz * k,
            yz: self.yz * k,
        }
    }

    /// Sum of the squares of all nine entries.
    fn squared_norm(&self) -> f64 {
        let diagonal = self.xx * self.xx + self.yy * self.yy + self.zz * self.zz;
        let off = self.xy * self.xy + self.xz * self.xz + self.yz * self.yz;
        diagonal + 2.0 * off
    }

    fn determinant(&self) -> f64 {
        let Self {
            xx,
            yy,
            zz,
            xy,
            xz,
            yz,
        } = *self;
        xx * (yy * zz - yz * yz) - xy * (xy * zz - yz * xz) + xz * (xy * yz - yy * xz)
    }

    fn mul(&self, v: DVec3) -> DVec3 {
        DVec3::new(
            self.xx * v.x + self.xy * v.y + self.xz * v.z,
            self.xy * v.x + self.yy * v.y + self.yz * v.z,
            self.xz * v.x + self.yz * v.y + self.zz * v.z,
        )
    }

    /// Unit vector spanning the null space of `self`, which must have rank
    /// 2: the largest cross product of two of its rows.
    fn null_vector(&self) -> DVec3 {
        let rows = [
            DVec3::new(self.xx, self.xy, self.xz),
            DVec3::new(self.xy, self.yy, self.yz),
            DVec3::new(self.xz, self.yz, self.zz),
        ];
        let crosses = [
            rows[0].cross(rows[1]),
            rows[0].cross(rows[2]),
            rows[1].cross(rows[2]),
        ];
        let mut best = crosses[0];
        let mut best_len2 = best.length_squared();
        for c in &crosses[1..] {
            let len2 = c.length_squared();
            if len2 > best_len2 {
                best = *c;
                best_len2 = len2;
            }
        }
        best * (1.0 / best_len2.sqrt())
    }
}
