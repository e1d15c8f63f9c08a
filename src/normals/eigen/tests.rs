//! Tests of the analytic solver: the contract on its own (ascending,
//! orthonormal, canonical sign, residuals) and agreement with the Jacobi
//! oracle, on matrices `R diag(l) R^T` with random rotations and spectra
//! that are generic, planar (PCA), near-repeated, exactly repeated, flat,
//! colinear and isotropic, at scales 1e-30 .. 1e30; plus fixed edge cases.

use glam::{DMat3, DQuat};
use proptest::prelude::*;

use super::*;
use crate::normals::pca::COLINEAR_TOLERANCE;
use crate::rng::Rng;

type Eigen = ([f64; 3], [DVec3; 3]);

fn rotation(q: [f64; 4]) -> DMat3 {
    DMat3::from_quat(DQuat::from_array(q).normalize())
}

fn random_rotation(rng: &mut Rng) -> DMat3 {
    rotation(std::array::from_fn(|_| rng.range(-1.0, 1.0)))
}

fn with_spectrum(r: DMat3, l: [f64; 3]) -> [[f64; 3]; 3] {
    let m = r * DMat3::from_diagonal(DVec3::from_array(l)) * r.transpose();
    std::array::from_fn(|i| m.row(i).to_array())
}

fn apply(m: &[[f64; 3]; 3], v: DVec3) -> DVec3 {
    DVec3::from_array(m.map(|row| DVec3::from_array(row).dot(v)))
}

fn magnitude(l: [f64; 3]) -> f64 {
    l.iter().fold(0.0, |s, x| s.max(x.abs()))
}

/// Angle between the lines of two unit vectors, accurate near zero.
fn line_angle(a: DVec3, b: DVec3) -> f64 {
    let angle = |b: DVec3| a.cross(b).length().atan2(a.dot(b));
    angle(b).min(angle(-b))
}

/// Ascending eigenvalues, orthonormal canonical eigenvectors, and residuals
/// `|A v - l v|` within 1e-12 of the largest |eigenvalue|.
fn check_contract(m: &[[f64; 3]; 3], (l, v): &Eigen, label: &str) {
    assert!(l[0] <= l[1] && l[1] <= l[2], "{label}: not ascending {l:?}");
    let scale = magnitude(*l);
    for i in 0..3 {
        assert_eq!(canonical_sign(v[i]), v[i], "{label}: sign of {:?}", v[i]);
        for j in 0..3 {
            let want = if i == j { 1.0 } else { 0.0 };
            let dot = v[i].dot(v[j]);
            assert!((dot - want).abs() <= 1e-12, "{label}: v{i}.v{j} = {dot}");
        }
        // Relative to the scale, so that 1e300 does not overflow the norm.
        let k = if scale > 0.0 { 1.0 / scale } else { 1.0 };
        let residual = (apply(m, v[i]) * k - (l[i] * k) * v[i]).length();
        assert!(
            residual <= 1e-12,
            "{label}: residual {residual} of pair {i}, eigenvalues {l:?}"
        );
    }
}

/// Eigenvalues within 1e-12 of the largest |eigenvalue| of Jacobi's, and the
/// smallest eigenvector within 1e-8 rad whenever `l1 - l0 > 1e-6 * |l|`.
fn check_against_jacobi(m: &[[f64; 3]; 3], (l, v): &Eigen, label: &str) {
    let (want, vectors) = sym3_eigen_jacobi(*m);
    let scale = magnitude(want);
    for i in 0..3 {
        let off = (l[i] - want[i]).abs();
        assert!(
            off <= 1e-12 * scale,
            "{label}: eigenvalues {l:?}, Jacobi {want:?}"
        );
    }
    if want[1] - want[0] > 1e-6 * scale {
        let angle = line_angle(v[0], vectors[0]);
        assert!(
            angle <= 1e-8,
            "{label}: smallest eigenvector {angle} rad off"
        );
    }
}

/// A spectrum of the given kind from `a, b` in (0, 1], `c` in [-1, 1] and a
/// relative gap `10^rel`, rel in [-15, -3].
fn spectrum(kind: usize, a: f64, b: f64, c: f64, rel: f64) -> [f64; 3] {
    let gap = 10f64.powf(rel);
    match kind {
        0 => [a, b, c],
        1 => [gap, 0.3 + 0.7 * b, 1.0],
        2 => [a, a * (1.0 + gap), b],
        3 => [b, a, a * (1.0 + gap)],
        4 => [a, a, c],
        5 => [c, a, a],
        6 => [0.0, a, b],
        7 => [0.0, a, a],
        8 => [0.0, 0.0, a],
        9 => [a, a * (1.0 + gap), a * (1.0 + 2.0 * gap)],
        10 => [-a, b * gap, c],
        _ => [a, a, a],
    }
}

const ISOTROPIC: usize = 11;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(4000))]
    #[test]
    fn random_rotations_meet_the_contract_and_match_jacobi(
        q in prop::array::uniform4(-1.0f64..1.0),
        kind in 0usize..=ISOTROPIC,
        a in 0.01f64..1.0,
        b in 0.01f64..1.0,
        c in -1.0f64..1.0,
        rel in -15.0f64..-3.0,
        exponent in -30i32..=30,
    ) {
        prop_assume!(DQuat::from_array(q).length() > 0.1);
        let scale = 10f64.powi(exponent);
        let l = spectrum(kind, a, b, c, rel).map(|x| x * scale);
        let m = with_spectrum(rotation(q), l);
        let got = analytic(&m);
        // Only an exactly isotropic shift can leave nothing to normalise.
        prop_assert!(got.is_some() || kind == ISOTROPIC, "fell back to Jacobi");
        let got = got.unwrap_or_else(|| sym3_eigen_jacobi(m));
        let label = format!("kind {kind}, spectrum {l:?}, m {m:?}");
        check_contract(&m, &got, &label);
        check_against_jacobi(&m, &got, &label);
    }
}

#[test]
fn realistic_covariances_of_noisy_planes_match_jacobi() {
    for seed in 0..20u64 {
        let mut rng = Rng::new(seed);
        for case in 0..500 {
            let r = random_rotation(&mut rng);
            let spacing2 = 10f64.powf(rng.range(-6.0, 2.0));
            let l = [10f64.powf(rng.range(-8.0, -1.0)), rng.range(0.2, 1.0), 1.0];
            let m = with_spectrum(r, l.map(|x| x * spacing2));
            let label = format!("seed {seed} case {case}, spectrum {l:?} * {spacing2}");
            let got = analytic(&m).unwrap_or_else(|| panic!("{label}: fell back"));
            check_contract(&m, &got, &label);
            check_against_jacobi(&m, &got, &label);
            let normal = r.col(0);
            let angle = line_angle(got.1[0], normal);
            assert!(angle < 1e-9, "{label}: normal {angle} rad off");
        }
    }
}

#[test]
fn colinear_and_flat_spectra_keep_the_colinear_test_exact() {
    for seed in 0..200u64 {
        let mut rng = Rng::new(seed);
        let r = random_rotation(&mut rng);
        let a = rng.range(0.1, 10.0);
        let (line, _) = sym3_eigen(with_spectrum(r, [0.0, 0.0, a]));
        assert!(
            line[1] - line[0] <= 1e-3 * COLINEAR_TOLERANCE * line[2],
            "seed {seed}: colinear gap {:e}",
            line[1] - line[0]
        );
        let (strip, _) = sym3_eigen(with_spectrum(r, [0.0, 1e-8 * a, a]));
        let gap = strip[1] - strip[0];
        assert!(
            (gap - 1e-8 * a).abs() <= 1e-13 * a,
            "seed {seed}: strip gap {gap:e}, want {:e}",
            1e-8 * a
        );
    }
}

#[test]
fn isolated_root_solves_the_normalised_cubic() {
    for i in 0..=2000 {
        let b = 2.0 * i as f64 / 2000.0;
        let t = isolated_root(b);
        let want = 2.0 * ((0.5 * b).acos() / 3.0).cos();
        assert!(
            (t - want).abs() <= 4.0 * f64::EPSILON,
            "b {b}: {t} vs {want}"
        );
    }
}

#[test]
fn diagonal_matrix_is_sorted_not_rotated() {
    let (l, v) = sym3_eigen([[3.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 2.0]]);
    assert_eq!(l, [-1.0, 2.0, 3.0]);
    assert_eq!(v, [DVec3::Y, DVec3::Z, DVec3::X]);
    let (l, v) = sym3_eigen([[2.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]);
    assert_eq!(l, [1.0, 1.0, 2.0]);
    assert_eq!(v, [DVec3::Y, DVec3::Z, DVec3::X]);
}

#[test]
fn zero_matrix_gives_zero_eigenvalues_and_axes() {
    let (l, v) = sym3_eigen([[0.0; 3]; 3]);
    assert_eq!(l, [0.0; 3]);
    assert_eq!(v, [DVec3::X, DVec3::Y, DVec3::Z]);
}

#[test]
fn two_by_two_block_splits_exactly() {
    let (l, v) = sym3_eigen([[1.0, 1.0, 0.0], [1.0, 1.0, 0.0], [0.0, 0.0, 5.0]]);
    assert!(l[0].abs() < 1e-15 && (l[1] - 2.0).abs() < 1e-15, "{l:?}");
    assert!((l[2] - 5.0).abs() <= 8.0 * f64::EPSILON, "{l:?}");
    let h = std::f64::consts::FRAC_1_SQRT_2;
    assert!((v[0] - DVec3::new(h, -h, 0.0)).length() < 1e-15, "{v:?}");
    assert!((v[1] - DVec3::new(h, h, 0.0)).length() < 1e-15, "{v:?}");
    assert_eq!(v[2], DVec3::Z);
}

#[test]
fn asymmetric_input_is_averaged() {
    let mut rng = Rng::new(3);
    let m = with_spectrum(random_rotation(&mut rng), [0.1, 0.4, 2.0]);
    let mut skew = m;
    for (i, j) in [(0, 1), (0, 2), (1, 2)] {
        skew[i][j] += 0.25;
        skew[j][i] -= 0.25;
    }
    let (l, v) = sym3_eigen(skew);
    check_contract(&m, &(l, v), "skewed");
    check_against_jacobi(&m, &(l, v), "skewed");
}

/// Spreads beyond ~1e145 (squares past 1e290) go to the prescaled Jacobi;
/// 1e140 still takes the analytic path. Both stay accurate.
#[test]
fn extreme_scales_stay_accurate() {
    let mut rng = Rng::new(11);
    let r = random_rotation(&mut rng);
    for scale in [1e300, 1e160, 1e140, 1e-140, 1e-160, 1e-300] {
        let l = [0.25 * scale, 0.5 * scale, scale];
        let m = with_spectrum(r, l);
        let label = format!("scale {scale:e}");
        let fallback = !(1e-145..=1e145).contains(&scale);
        assert_eq!(analytic(&m).is_none(), fallback, "{label}");
        let got = sym3_eigen(m);
        check_contract(&m, &got, &label);
        for (value, want) in got.0.iter().zip(l) {
            assert!(
                (value - want).abs() <= 1e-14 * scale,
                "{label}: {:?}",
                got.0
            );
        }
    }
}

#[test]
fn non_finite_input_returns_without_panicking() {
    let nan = f64::NAN;
    let inf = f64::INFINITY;
    let inputs = [
        [[nan; 3]; 3],
        [[1.0, nan, 0.0], [nan, 2.0, 0.5], [0.0, 0.5, 3.0]],
        [[1.0, 0.5, 0.0], [0.5, nan, 0.5], [0.0, 0.5, 3.0]],
        [[inf, 1.0, 0.0], [1.0, 2.0, 0.5], [0.0, 0.5, 3.0]],
        [[1.0, -inf, 0.0], [-inf, 2.0, 0.5], [0.0, 0.5, 3.0]],
        [
            [1e308, 1e308, 0.0],
            [1e308, -1e308, 1e308],
            [0.0, 1e308, 1e308],
        ],
    ];
    for m in inputs {
        let (l, v) = sym3_eigen(m);
        let finite = l.iter().all(|x| x.is_finite()) && v.iter().all(|x| x.is_finite());
        assert!(
            !finite || m.iter().flatten().all(|x| x.is_finite()),
            "{m:?}"
        );
    }
}

#[test]
fn subnormal_entries_give_an_orthonormal_basis() {
    let m = [
        [4e-320, 1e-320, 0.0],
        [1e-320, 2e-320, 0.0],
        [0.0, 0.0, 1e-320],
    ];
    let (l, v) = sym3_eigen(m);
    assert!(l[0] <= l[1] && l[1] <= l[2], "{l:?}");
    for i in 0..3 {
        assert!((v[i].length() - 1.0).abs() < 1e-12, "{v:?}");
    }
}

#[test]
fn canonical_sign_flips_to_the_first_largest_component() {
    let oracle = |v: DVec3| {
        let a = v.to_array();
        let big = v.abs().max_element();
        let first = a.iter().position(|c| c.abs() == big).unwrap_or(0);
        if a[first] < 0.0 {
            -v
        } else {
            v
        }
    };
    let mut rng = Rng::new(5);
    let grid = [-2.0, -1.0, -0.0, 0.0, 1.0, 2.0];
    for x in grid {
        for y in grid {
            for z in grid {
                let v = DVec3::new(x, y, z);
                assert_eq!(canonical_sign(v), oracle(v), "{v:?}");
            }
        }
    }
    for _ in 0..1000 {
        let v = DVec3::new(rng.normal(), rng.normal(), rng.normal());
        assert_eq!(canonical_sign(v), oracle(v), "{v:?}");
    }
}
