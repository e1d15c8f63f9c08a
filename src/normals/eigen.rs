//! Eigen-decomposition of symmetric 3x3 matrices, for the PCA tangent planes
//! of paper 1 section 2.3 (the smallest eigenpair of the covariance).
//!
//! Method: cyclic Jacobi rotations. The paper suggests inverse iteration for
//! the smallest eigenpair alone; we want all three eigenvalues (surface
//! variation, degeneracy tests) and, above all, robustness where analytic
//! cubic-root solvers are fragile: repeated eigenvalues (exactly flat or
//! exactly linear neighbourhoods, LAS data quantised to a grid; Open3D #880)
//! and zero matrices. Jacobi needs no special case for either: a zero
//! off-diagonal is simply never rotated, every rotation is orthogonal so the
//! eigenvectors stay orthonormal to rounding, and it converges quadratically
//! (a 3x3 needs 3-5 sweeps of 3 rotations). It costs about a thousand
//! instructions per matrix (callgrind), well inside the normals budget.

use glam::DVec3;

/// Sweeps are bounded so that no input (even NaN) can loop forever; converged
/// matrices stop after a handful.
const MAX_SWEEPS: usize = 32;
/// Converged when the off-diagonal mass is below (eps/4)^2 of the diagonal
/// mass: what is left moves eigenvalues by less than rounding already does.
const CONVERGED: f64 = f64::EPSILON * f64::EPSILON / 16.0;
/// Beyond this |theta| the rotation angle is computed without squaring theta.
const HUGE_THETA: f64 = 1e150;

/// Eigenvalues in ascending order and matching orthonormal eigenvectors of
/// the symmetric matrix `m` (its upper and lower triangles are averaged).
///
/// Each eigenvector has a canonical sign: its component of largest magnitude
/// is positive (on equal magnitudes, the first such axis). For exactly
/// repeated eigenvalues the basis of the eigenspace is whatever the rotations
/// produced, deterministic for a given input. A zero matrix gives zero
/// eigenvalues and the unit axes.
pub fn sym3_eigen(m: [[f64; 3]; 3]) -> ([f64; 3], [DVec3; 3]) {
    let mut a = symmetrised(m);
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
    let values = order.map(|i| a[i][i]);
    let vectors = order.map(|i| canonical_sign(DVec3::new(v[0][i], v[1][i], v[2][i])));
    (values, vectors)
}

/// Flips `v` so that its component of largest magnitude is positive (the
/// first axis among equal magnitudes).
pub fn canonical_sign(v: DVec3) -> DVec3 {
    let abs = v.abs().to_array();
    let mut axis = 0;
    for i in 1..3 {
        if abs[i] > abs[axis] {
            axis = i;
        }
    }
    if v.to_array()[axis] < 0.0 {
        -v
    } else {
        v
    }
}

fn symmetrised(m: [[f64; 3]; 3]) -> [[f64; 3]; 3] {
    std::array::from_fn(|i| std::array::from_fn(|j| 0.5 * (m[i][j] + m[j][i])))
}

/// One Jacobi rotation in the (p, q) plane that zeroes `a[p][q]`, applied to
/// `a` (two-sided) and accumulated into the eigenvector columns of `v`.
fn rotate(a: &mut [[f64; 3]; 3], v: &mut [[f64; 3]; 3], p: usize, q: usize) {
    let apq = a[p][q];
    if apq == 0.0 {
        return;
    }
    let theta = (a[q][q] - a[p][p]) / (2.0 * apq);
    let t = if theta.abs() > HUGE_THETA {
        0.5 / theta
    } else {
        theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt())
    };
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn diagonal_matrix_is_sorted_not_rotated() {
        let (l, v) = sym3_eigen([[3.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 2.0]]);
        assert_eq!(l, [-1.0, 2.0, 3.0]);
        assert_eq!(v, [DVec3::Y, DVec3::Z, DVec3::X]);
    }

    #[test]
    fn two_by_two_block_splits_exactly() {
        let (l, v) = sym3_eigen([[1.0, 1.0, 0.0], [1.0, 1.0, 0.0], [0.0, 0.0, 5.0]]);
        assert!(l[0].abs() < 1e-15 && (l[1] - 2.0).abs() < 1e-15 && l[2] == 5.0);
        let h = std::f64::consts::FRAC_1_SQRT_2;
        assert!(
            (v[0] - DVec3::new(h, -h, 0.0)).length() < 1e-15,
            "{:?}",
            v[0]
        );
        assert_eq!(v[2], DVec3::Z);
    }
}
