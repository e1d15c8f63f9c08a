//! The symmetric 3x3 eigen-solver and the PCA plane fit against constructed
//! answers: matrices built as R diag(l) R^T, exact planes, lines, points, and
//! a sphere whose normals are known.

use glam::{DMat3, DQuat, DVec3};
use scanmesh::normals::eigen::sym3_eigen;
use scanmesh::normals::pca::{fit_plane, fit_plane_points, Degenerate};
use scanmesh::spatial::{brute_knn, Neighbour};
use scanmesh::synth::{fibonacci_sphere, Rng};

/// A random rotation (normalised random quaternion).
fn rotation(rng: &mut Rng) -> DMat3 {
    let mut c = || rng.range(-1.0, 1.0);
    DMat3::from_quat(DQuat::from_xyzw(c(), c(), c(), c()).normalize())
}

const UTM: DVec3 = DVec3::new(5.0e5, 4.2e6, 310.0);

fn to_rows(m: DMat3) -> [[f64; 3]; 3] {
    std::array::from_fn(|i| m.row(i).to_array())
}

/// Angle between two unit vectors, accurate near zero (unlike acos).
fn angle(a: DVec3, b: DVec3) -> f64 {
    a.cross(b).length().atan2(a.dot(b))
}

/// Angle between the lines of two unit vectors (sign ignored).
fn line_angle(a: DVec3, b: DVec3) -> f64 {
    angle(a, b).min(angle(a, -b))
}

fn frobenius(m: [[f64; 3]; 3]) -> f64 {
    m.iter().flatten().map(|x| x * x).sum::<f64>().sqrt()
}

/// Eigenvalue triples with distinct, repeated, zero, negative and extreme
/// entries; `s` scales them.
fn spectra(rng: &mut Rng) -> Vec<[f64; 3]> {
    let (a, b, c) = (
        rng.range(0.1, 10.0),
        rng.range(0.1, 10.0),
        rng.range(-10.0, 10.0),
    );
    let mut out = vec![
        [a, b, c],
        [a, a, b],
        [a, b, b],
        [a, a, a],
        [0.0, 0.0, a],
        [0.0, a, a],
        [0.0, a, b],
        [0.0, 0.0, 0.0],
        [-a, -a, b],
        [a, a * (1.0 + 1e-9), b],
    ];
    let s = [1e-12, 1e12][(rng.next_u64() % 2) as usize];
    out.push([a * s, b * s, c * s]);
    out.push([0.0, a * s, a * s]);
    out
}

#[test]
fn eigen_reconstructs_random_rotations() {
    for seed in 0..300u64 {
        let mut rng = Rng::new(seed);
        for l in spectra(&mut rng) {
            let r = rotation(&mut rng);
            let m = to_rows(r * DMat3::from_diagonal(DVec3::from_array(l)) * r.transpose());
            let (values, vectors) = sym3_eigen(m);
            let scale = l.iter().fold(0.0f64, |s, x| s.max(x.abs()));
            let mut want = l;
            want.sort_by(f64::total_cmp);
            for i in 0..3 {
                assert!(
                    (values[i] - want[i]).abs() <= 1e-9 * scale,
                    "seed {seed} l {l:?}: eigenvalues {values:?}"
                );
                for j in 0..3 {
                    let dot = vectors[i].dot(vectors[j]);
                    let expect = if i == j { 1.0 } else { 0.0 };
                    assert!(
                        (dot - expect).abs() < 1e-12,
                        "seed {seed} l {l:?}: not orthonormal"
                    );
                }
            }
            let v = DMat3::from_cols(vectors[0], vectors[1], vectors[2]);
            let back = to_rows(v * DMat3::from_diagonal(DVec3::from_array(values)) * v.transpose());
            let diff: [[f64; 3]; 3] =
                std::array::from_fn(|i| std::array::from_fn(|j| back[i][j] - m[i][j]));
            assert!(
                frobenius(diff) <= 1e-9 * frobenius(m),
                "seed {seed} l {l:?}: reconstruction off by {}",
                frobenius(diff)
            );
        }
    }
}

#[test]
fn eigenvectors_have_canonical_sign() {
    for seed in 0..100u64 {
        let mut rng = Rng::new(seed);
        let r = rotation(&mut rng);
        let m = to_rows(r * DMat3::from_diagonal(DVec3::new(1.0, 2.0, 3.0)) * r.transpose());
        for v in sym3_eigen(m).1 {
            let big = v.abs().max_element();
            let first = v.to_array().into_iter().find(|c| c.abs() == big);
            assert!(first.is_some_and(|c| c > 0.0), "seed {seed}: {v:?}");
        }
    }
}

#[test]
fn zero_matrix_gives_zero_eigenvalues_and_axes() {
    let (values, vectors) = sym3_eigen([[0.0; 3]; 3]);
    assert_eq!(values, [0.0; 3]);
    assert_eq!(vectors, [DVec3::X, DVec3::Y, DVec3::Z]);
}

/// A (2m+1)^2 grid in the plane spanned by `u`, `v` through `origin`.
fn planar_grid(origin: DVec3, u: DVec3, v: DVec3, m: i32) -> Vec<DVec3> {
    let mut pts = vec![origin];
    for i in -m..=m {
        for j in -m..=m {
            if (i, j) != (0, 0) {
                pts.push(origin + u * i as f64 + v * j as f64);
            }
        }
    }
    pts
}

#[test]
fn axis_planes_at_utm_offsets_give_exact_normals() {
    let cases = [
        (DVec3::X * 0.25, DVec3::Y * 0.5, DVec3::Z),
        (DVec3::Y * 0.1, DVec3::Z * 0.1, DVec3::X),
        (DVec3::Z * 2.0, DVec3::X * 0.01, DVec3::Y),
    ];
    for (u, v, normal) in cases {
        for offset in [DVec3::ZERO, UTM, -UTM] {
            let pts = planar_grid(offset + DVec3::new(0.125, -3.5, 7.0), u, v, 2);
            let fit = fit_plane_points(&pts).expect("planar grid");
            assert_eq!(fit.normal, normal, "offset {offset:?}");
            assert_eq!(fit.eigenvalues[0], 0.0);
            assert_eq!(fit.surface_variation(), 0.0);
            assert!((fit.centroid - pts[0]).length() < 1e-9);
        }
    }
}

#[test]
fn tilted_plane_at_utm_offset_gives_its_normal() {
    // (2,-1,0) and (2,0,-1) are orthogonal to (1,2,2); the points are exact in f64.
    let normal = DVec3::new(1.0, 2.0, 2.0) / 3.0;
    let (u, v) = (
        DVec3::new(2.0, -1.0, 0.0) * 0.125,
        DVec3::new(2.0, 0.0, -1.0) * 0.125,
    );
    let pts = planar_grid(UTM, u, v, 3);
    let nbrs: Vec<Neighbour> = (1..pts.len() as u32)
        .map(|index| Neighbour { dist2: 0.0, index })
        .collect();
    let fit = fit_plane(&pts, 0, &nbrs).expect("tilted plane");
    assert!(angle(fit.normal, normal) < 1e-12, "normal {:?}", fit.normal);
    assert!(fit.surface_variation() < 1e-24);
}

#[test]
fn colinear_coincident_and_too_few_are_reported() {
    let dir = DVec3::new(0.3, -0.2, 0.9).normalize();
    let line: Vec<DVec3> = (0..13).map(|i| UTM + dir * (0.05 * i as f64)).collect();
    assert_eq!(fit_plane_points(&line), Err(Degenerate::Colinear));
    let axis_line: Vec<DVec3> = (0..13).map(|i| UTM + DVec3::X * i as f64).collect();
    assert_eq!(fit_plane_points(&axis_line), Err(Degenerate::Colinear));
    assert_eq!(fit_plane_points(&[UTM; 12]), Err(Degenerate::Coincident));
    assert_eq!(
        fit_plane_points(&[UTM, UTM + DVec3::X]),
        Err(Degenerate::TooFew)
    );
    assert_eq!(fit_plane_points(&[]), Err(Degenerate::TooFew));
    let pts = [UTM, UTM + DVec3::X, UTM + DVec3::Y];
    let one = [Neighbour {
        dist2: 1.0,
        index: 1,
    }];
    assert_eq!(fit_plane(&pts, 0, &one), Err(Degenerate::TooFew));
    let bad = [
        one[0],
        Neighbour {
            dist2: 1.0,
            index: 9,
        },
    ];
    assert_eq!(fit_plane(&pts, 0, &bad), Err(Degenerate::TooFew));
    assert_eq!(fit_plane(&pts, 5, &one), Err(Degenerate::TooFew));
}

#[test]
fn cube_corners_leave_the_normal_undetermined() {
    let corners: Vec<DVec3> = (0..8)
        .map(|i| UTM + DVec3::new((i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64))
        .collect();
    assert_eq!(fit_plane_points(&corners), Err(Degenerate::Colinear));
}

#[test]
fn sphere_neighbourhoods_give_radial_normals() {
    let pts = fibonacci_sphere(UTM, 1.0, 5000);
    let tie: Vec<u64> = (0..pts.len() as u64).collect();
    for i in (0..pts.len()).step_by(37) {
        let nbrs = brute_knn(&pts, &tie, pts[i], 12, Some(i as u32));
        let fit = fit_plane(&pts, i, &nbrs).expect("sphere patch");
        let radial = (pts[i] - UTM).normalize();
        let off = line_angle(fit.normal, radial);
        // 12 neighbours span r ~ 0.1 rad of the unit sphere; an off-centre
        // neighbourhood tilts the plane by a fraction of r (observed 0.015).
        // About its centroid's own radial the tilt is second order in r
        // (observed 3.6e-3), and the surface variation O(r^2) (5.5e-4).
        assert!(
            off < 0.03,
            "point {i}: normal {:?} is {off} rad off radial",
            fit.normal
        );
        let at_centroid = (fit.centroid - UTM).normalize();
        let off_c = line_angle(fit.normal, at_centroid);
        assert!(
            off_c < 5e-3,
            "point {i}: {off_c} rad off the centroid's radial"
        );
        let sv = fit.surface_variation();
        assert!(sv > 0.0 && sv < 2e-3, "point {i}: surface variation {sv}");
    }
}
