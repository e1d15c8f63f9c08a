//! Distances: analytic surfaces (icosphere, plane, lattice) and a seeded
//! brute-force oracle for the accelerated nearest-triangle query.

use super::{permutation, v};
use glam::{DVec2, DVec3};
use scanmesh::mesh::distance::{
    closest_point_on_triangle, compare_with, point_triangle_distance2, stats, CompareOptions,
};
use scanmesh::mesh::{compare, point_to_mesh_distances, shapes, Mesh, Reference};

/// SplitMix64 uniforms, so every failure can name its seed.
struct Rng(u64);
impl Rng {
    fn f64(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.f64()
    }
    fn point(&mut self, lo: f64, hi: f64) -> DVec3 {
        v(self.range(lo, hi), self.range(lo, hi), self.range(lo, hi))
    }
    fn direction(&mut self) -> DVec3 {
        loop {
            let p = self.point(-1.0, 1.0);
            if p.length_squared() > 1e-6 && p.length_squared() <= 1.0 {
                return p.normalize();
            }
        }
    }
}

/// Outward unit normal and plane offset of each face of a convex mesh.
fn planes(m: &Mesh) -> Vec<(DVec3, f64)> {
    m.triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| m.vertices[i as usize]);
            let n = (b - a).cross(c - a).normalize();
            (n, n.dot(a))
        })
        .collect()
}

#[test]
fn icosphere_matches_convex_polyhedron_geometry() {
    let m = shapes::icosphere(3);
    let mut rng = Rng(7);
    // Radially outside a vertex, that vertex is nearest: d = r - 1.
    let radii: Vec<f64> = m.vertices.iter().map(|_| rng.range(1.01, 3.0)).collect();
    let pts: Vec<DVec3> = m
        .vertices
        .iter()
        .zip(&radii)
        .map(|(p, r)| *p * *r)
        .collect();
    for (i, d) in point_to_mesh_distances(&pts, &m).iter().enumerate() {
        let want = radii[i] * m.vertices[i].length() - m.vertices[i].length();
        assert!(
            (d - want).abs() < 1e-12,
            "seed 7, vertex {i}: {d} vs {want}"
        );
    }
    // Radially outside a face centroid, the foot lies in the face: the
    // distance is the height over the face plane.
    let planes = planes(&m);
    let pts: Vec<DVec3> = m
        .triangles
        .iter()
        .map(|t| {
            let c = t.iter().map(|&i| m.vertices[i as usize]).sum::<DVec3>() / 3.0;
            c.normalize() * rng.range(1.0, 2.0)
        })
        .collect();
    for (f, d) in point_to_mesh_distances(&pts, &m).iter().enumerate() {
        let (n, off) = planes[f];
        let want = n.dot(pts[f]) - off;
        assert!((d - want).abs() < 1e-12, "seed 7, face {f}: {d} vs {want}");
    }
    // Inside a convex body, the distance to the boundary is the nearest
    // face plane.
    let inradius = planes.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
    let d = point_to_mesh_distances(&[DVec3::ZERO], &m)[0];
    assert!((d - inradius).abs() < 1e-14, "{d} vs {inradius}");
}

#[test]
fn unit_sphere_points_lie_within_the_sagitta() {
    let seed = 11;
    let m = shapes::icosphere(4);
    let inradius = planes(&m).iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
    let sagitta = 1.0 - inradius;
    let mut rng = Rng(seed);
    let pts: Vec<DVec3> = (0..20_000).map(|_| rng.direction()).collect();
    let r = compare(&m, Reference::Points(&pts));
    let to_mesh = r.reference_to_mesh.absolute.unwrap();
    assert!(
        to_mesh.max <= sagitta + 1e-15,
        "seed {seed}: {} > {sagitta}",
        to_mesh.max
    );
    assert!(
        to_mesh.max > 0.5 * sagitta,
        "seed {seed}: some point near a face centre"
    );
    assert!(to_mesh.mean < to_mesh.rms && to_mesh.rms <= to_mesh.max);
    assert!(to_mesh.p95 <= to_mesh.max);
    assert_eq!(
        r.hausdorff,
        Some(to_mesh.max.max(r.mesh_to_reference.absolute.unwrap().max))
    );
}

#[test]
fn plane_versus_offset_points_is_exact() {
    let seed = 3;
    let m = shapes::grid(10, 10, DVec2::ONE);
    let mut rng = Rng(seed);
    let heights: Vec<f64> = (0..5000).map(|_| rng.range(-0.5, 0.5)).collect();
    let pts: Vec<DVec3> = heights
        .iter()
        .map(|&h| v(rng.range(0.0, 1.0), rng.range(0.0, 1.0), h))
        .collect();
    for (i, d) in point_to_mesh_distances(&pts, &m).iter().enumerate() {
        assert!(
            (d - heights[i].abs()).abs() <= 1e-15,
            "seed {seed}, point {i}"
        );
    }
    let abs: Vec<f64> = heights.iter().map(|h| h.abs()).collect();
    let mean = abs.iter().sum::<f64>() / abs.len() as f64;
    let max = abs.iter().copied().fold(0.0, f64::max);
    let r = compare(&m, Reference::Points(&pts)).reference_to_mesh;
    let got = r.absolute.unwrap();
    assert_eq!(r.points, 5000);
    assert!(
        (got.mean - mean).abs() < 1e-15,
        "seed {seed}: mean {} vs {mean}",
        got.mean
    );
    assert!(
        (got.max - max).abs() < 1e-15,
        "seed {seed}: max {} vs {max}",
        got.max
    );
    let mut sorted = abs.clone();
    sorted.sort_by(f64::total_cmp);
    assert!(
        (got.p95 - sorted[4750 - 1]).abs() < 1e-15,
        "nearest rank 4750 of 5000"
    );
    assert!(
        (got.p999 - sorted[4995 - 1]).abs() < 1e-15,
        "nearest rank 4995 of 5000"
    );
    // The maximum is reported where it is: the point of largest |height|.
    let far = (0..abs.len()).fold(0, |a, b| if abs[b] > abs[a] { b } else { a });
    assert_eq!(r.max_at, Some(pts[far].to_array()));
}

#[test]
fn lattice_reference_gives_spacing_units() {
    // Points on a 0.1 lattice, 0.05 above the unit square.
    let pts: Vec<DVec3> = (0..=10)
        .flat_map(|j| (0..=10).map(move |i| v(i as f64 * 0.1, j as f64 * 0.1, 0.05)))
        .collect();
    let m = shapes::grid(4, 4, DVec2::ONE);
    let r = compare(&m, Reference::Points(&pts));
    let spacing = r.reference_spacing.unwrap();
    assert!((spacing - 0.1).abs() < 1e-12, "{spacing}");
    let rel = r.reference_to_mesh.in_spacing.unwrap();
    assert!((rel.max - 0.5).abs() < 1e-9 && (rel.mean - 0.5).abs() < 1e-9);
}

#[test]
fn mesh_against_itself_and_a_scaled_copy() {
    let m = shapes::icosphere(3);
    let same = compare(&m, Reference::Mesh(&m));
    assert!(same.hausdorff.unwrap() < 1e-12, "{:?}", same.hausdorff);
    assert!(same.mesh_samples >= 10_000 && same.reference_samples >= 10_000);
    // Scaled by 1.02: every scaled vertex sits 0.02 radially outside a
    // vertex of the unit mesh, and nothing of the surfaces is further
    // apart than 0.02 plus the sagitta.
    let big = Mesh::new(
        m.vertices.iter().map(|p| *p * 1.02).collect(),
        m.triangles.clone(),
    );
    let opts = CompareOptions {
        samples: Some(0),
        ..Default::default()
    };
    let r = compare_with(&big, Reference::Mesh(&m), &opts);
    let a = r.mesh_to_reference.absolute.unwrap();
    assert!(
        (a.max - 0.02).abs() < 1e-12 && (a.mean - 0.02).abs() < 1e-12,
        "{a:?}"
    );
    assert_eq!(r.mesh_samples, 0);
}

#[test]
fn results_do_not_depend_on_the_thread_count() {
    let m = shapes::torus(2.0, 0.7, 30, 12);
    let mut rng = Rng(5);
    let pts: Vec<DVec3> = (0..3000).map(|_| rng.point(-3.0, 3.0)).collect();
    let run = |threads| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| compare(&m, Reference::Points(&pts)))
    };
    assert_eq!(run(1), run(2));
}

#[test]
fn empty_targets_report_nothing_to_measure() {
    let empty = Mesh::default();
    let r = compare(&empty, Reference::Points(&[v(0., 0., 0.), v(1., 0., 0.)]));
    assert_eq!(r.reference_to_mesh.absolute, None);
    assert_eq!(r.hausdorff, None);
    assert_eq!(stats(Vec::new()), None);
    assert_eq!(
        point_to_mesh_distances(&[DVec3::ONE], &empty),
        [f64::INFINITY]
    );
}

/// A random triangle, sometimes thin or collapsed, to exercise every region.
fn random_triangle(rng: &mut Rng) -> [DVec3; 3] {
    let a = rng.point(-1.0, 1.0);
    let size = rng.range(0.01, 0.6);
    let b = a + rng.point(-size, size);
    let c = match (rng.f64() * 10.0) as u32 {
        0 => a + (b - a) * rng.range(-1.0, 2.0), // collinear
        1 => a,                                  // repeated corner
        _ => a + rng.point(-size, size),
    };
    [a, b, c]
}

#[test]
fn closest_point_is_in_the_triangle_and_no_sample_is_closer() {
    for seed in [1u64, 2, 3, 99, 2024] {
        let mut rng = Rng(seed);
        for case in 0..300 {
            let [a, b, c] = random_triangle(&mut rng);
            let p = rng.point(-2.0, 2.0);
            let q = closest_point_on_triangle(p, a, b, c);
            let d = (p - q).length();
            // Dense barycentric samples give an upper bound on the true
            // distance: nothing may beat the reported point.
            let n = 60;
            for i in 0..=n {
                for j in 0..=(n - i) {
                    let (s, t) = (i as f64 / n as f64, j as f64 / n as f64);
                    let x = a + (b - a) * s + (c - a) * t;
                    assert!(d <= (p - x).length() + 1e-12, "seed {seed}, case {case}");
                }
            }
            // And q lies in the triangle: its area split is exact.
            let whole = (b - a).cross(c - a).length();
            let parts = (a - q).cross(b - q).length()
                + (b - q).cross(c - q).length()
                + (c - q).cross(a - q).length();
            assert!(
                (parts - whole).abs() <= 1e-9,
                "seed {seed}, case {case}: q outside"
            );
        }
    }
}

#[test]
fn accelerated_query_equals_brute_force() {
    for seed in [17u64, 18, 19, 4242] {
        let mut rng = Rng(seed);
        let mut m = Mesh::default();
        for _ in 0..400 {
            let base = m.vertices.len() as u32;
            m.vertices.extend(random_triangle(&mut rng));
            m.triangles.push([base, base + 1, base + 2]);
        }
        // Shuffle so tree order and input order differ.
        let order = permutation(m.triangles.len(), seed);
        m.triangles = order.iter().map(|&t| m.triangles[t]).collect();
        let pts: Vec<DVec3> = (0..2000).map(|_| rng.point(-1.5, 1.5)).collect();
        let fast = point_to_mesh_distances(&pts, &m);
        for (i, &p) in pts.iter().enumerate() {
            let brute = m
                .triangles
                .iter()
                .map(|t| {
                    let [a, b, c] = t.map(|k| m.vertices[k as usize]);
                    point_triangle_distance2(p, a, b, c)
                })
                .fold(f64::INFINITY, f64::min)
                .sqrt();
            assert_eq!(fast[i], brute, "seed {seed}, point {i} at {p}");
        }
    }
}
