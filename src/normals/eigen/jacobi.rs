//! Cyclic Jacobi rotations for symmetric 3x3 matrices: the solver's fallback
//! for inputs the analytic path declines (non-finite entries, spreads below
//! the normal range) and the oracle its tests and bench compare against.
//!
//! Jacobi needs no special case for repeated eigenvalues or zero matrices: a
//! zero off-diagonal is simply never rotated, every rotation is orthogonal so
//! the eigenvectors stay orthonormal to rounding, and it converges
//! quadratically (a 3x3 needs 3-5 sweeps of 3 rotations).

use glam::DVec3;

use super::canonical_sign;

/// Sweeps are bounded so that no input (even NaN) can loop forever; converged
/// matrices stop after a handful.
const MAX_SWEEPS: usize = 32;
/// Converged when the off-diagonal mass is below (eps/4)^2 of the diagonal
/// mass: what is left moves eigenvalues by less than rounding already does.
const CONVERGED: f64 = f64::EPSILON * f64::EPSILON / 16.0;
/// Beyond this |theta| the rotation angle is computed without squaring theta.
const HUGE_THETA: f64 = 1e150;
/// The exponent bits of an f64.
const EXPONENT_BITS: u64 = 0x7ff0_0000_0000_0000;

/// [`super::sym3_eigen`]'s contract, by cyclic Jacobi rotations (about 1600
/// instructions per matrix, callgrind). The entries are first divided by a
/// power of two near the largest magnitude (exact), so the squared masses of
/// the convergence test neither overflow nor underflow.
pub fn sym3_eigen_jacobi(m: [[f64; 3]; 3]) -> ([f64; 3], [DVec3; 3]) {
    let a = symmetrised(m);
    let scale = power_of_two_near_max(&a);
    let mut a = a.map(|row| row.map(|x| x / scale));
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for _ in 0..MAX_SWEEPS {
        let off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
        let diag = a[0][0] * a[0][0] + a[1][1] * a[1][1] + a[2][2] * a[2][2];
        if off <= CONVERGED * diag {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            rotate(&mut a, &mut v, p, q);
        }
    }
    let mut order = [0usize, 1, 2];
    order.sort_by(|&i, &j| a[i][i].total_cmp(&a[j][j]).then(i.cmp(&j)));
    let values = order.map(|i| a[i][i] * scale);
    let vectors = order.map(|i| canonical_sign(DVec3::new(v[0][i], v[1][i], v[2][i])));
    (values, vectors)
}

fn symmetrised(m: [[f64; 3]; 3]) -> [[f64; 3]; 3] {
    std::array::from_fn(|i| std::array::from_fn(|j| 0.5 * (m[i][j] + m[j][i])))
}

/// `2^floor(log2(max |a_ij|))`, or 1 when that is zero, subnormal or not
/// finite (nothing to gain, or nothing to save).
fn power_of_two_near_max(a: &[[f64; 3]; 3]) -> f64 {
    let max = a.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
    if (f64::MIN_POSITIVE..=f64::MAX).contains(&max) {
        f64::from_bits(max.to_bits() & EXPONENT_BITS)
    } else {
        1.0
    }
}

/// `tan` of the Jacobi rotation angle that zeroes the off-diagonal entry of
/// a 2x2 block with `theta = (a_qq - a_pp) / (2 a_pq)`: the root of
/// `t^2 + 2 theta t - 1 = 0` of smaller magnitude, so `|t| <= 1`.
pub(super) fn rotation_tangent(theta: f64) -> f64 {
    if theta.abs() > HUGE_THETA {
        0.5 / theta
    } else {
        theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt())
    }
}

/// One Jacobi rotation in the (p, q) plane that zeroes `a[p][q]`, applied to
/// `a` (two-sided) and accumulated into the eigenvector columns of `v`.
fn rotate(a: &mut [[f64; 3]; 3], v: &mut [[f64; 3]; 3], p: usize, q: usize) {
    let apq = a[p][q];
    if apq == 0.0 {
        return;
    }
    let t = rotation_tangent((a[q][q] - a[p][p]) / (2.0 * apq));
    let c = 1.0 / (t * t + 1.0).sqrt();
    let s = t * c;
    a[p][p] -= t * apq;
    a[q][q] += t * apq;
    a[p][q] = 0.0;
    a[q][p] = 0.0;
    let r = 3 - p - q;
    let (arp, arq) = (a[r][p], a[r][q]);
    a[r][p] = c * arp - s * arq;
    a[p][r] = a[r][p];
    a[r][q] = s * arp + c * arq;
    a[q][r] = a[r][q];
    for row in v.iter_mut() {
        let (vp, vq) = (row[p], row[q]);
        row[p] = c * vp - s * vq;
        row[q] = s * vp + c * vq;
    }
}
