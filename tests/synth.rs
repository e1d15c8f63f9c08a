//! Synthetic scans against their analytic truth: positions on the surface,
//! normals equal to the (independently derived) gradient, densities by
//! counting, determinism, chunked streaming, noise statistics and the mean
//! spacing hint against brute force. Every assertion names its seed.

use glam::{DVec2, DVec3};
use scanmesh::synth::{
    generate, mean_spacing_hint, stream, Building, Scan, Shape, SynthError, Terrain, TriMesh,
};

const EPS: f64 = 1e-12;

fn scan(shape: &Shape, n: usize, noise: f64, seed: u64) -> Scan {
    generate(shape, n, noise, seed).unwrap_or_else(|e| panic!("seed {seed}: {e}"))
}

fn assert_unit(n: DVec3, seed: u64, i: usize) {
    assert!(
        (n.length() - 1.0).abs() < EPS,
        "seed {seed} point {i}: |n| = {}",
        n.length()
    );
}

fn assert_close(a: DVec3, b: DVec3, tol: f64, what: &str, seed: u64, i: usize) {
    assert!(
        (a - b).length() < tol,
        "seed {seed} point {i}: {what} {a} vs {b}"
    );
}

/// Pearson chi-square of observed counts against expected probabilities.
fn chi_square(counts: &[usize], probs: &[f64]) -> f64 {
    let n: usize = counts.iter().sum();
    counts
        .iter()
        .zip(probs)
        .map(|(&c, &p)| {
            let e = p * n as f64;
            (c as f64 - e).powi(2) / e
        })
        .sum()
}

#[test]
fn sphere_points_normals_and_uniformity() {
    let seed = 1;
    let centre = DVec3::new(1.0, -2.0, 3.0);
    let s = scan(&Shape::sphere(centre, 2.5), 50_000, 0.0, seed);
    let mut bins = [0usize; 10];
    for (i, (&p, &n)) in s.points.iter().zip(&s.normals).enumerate() {
        assert!(
            ((p - centre).length() - 2.5).abs() < EPS * 2.5,
            "seed {seed} point {i}"
        );
        assert_unit(n, seed, i);
        assert_close(n, (p - centre) / 2.5, EPS, "normal", seed, i);
        // Archimedes: z is uniform on [-r, r] for area-uniform samples.
        bins[(((p.z - centre.z) / 2.5 + 1.0) * 5.0).clamp(0.0, 9.0) as usize] += 1;
    }
    let chi = chi_square(&bins, &[0.1; 10]);
    assert!(
        chi < 27.88,
        "seed {seed}: z histogram chi2 {chi} (df 9, p 0.001)"
    );
}

#[test]
fn torus_on_surface_with_gradient_normals() {
    let (seed, big_r, r) = (2, 2.0, 0.5);
    let s = scan(&Shape::torus(big_r, r), 40_000, 0.0, seed);
    let mut outer = 0usize;
    for (i, (&p, &n)) in s.points.iter().zip(&s.normals).enumerate() {
        let rho = p.truncate().length();
        let f = (rho - big_r).powi(2) + p.z * p.z - r * r;
        assert!(f.abs() < EPS, "seed {seed} point {i}: implicit {f}");
        let grad = DVec3::new((rho - big_r) * p.x / rho, (rho - big_r) * p.y / rho, p.z);
        assert_unit(n, seed, i);
        assert_close(n, grad.normalize(), 1e-9, "normal", seed, i);
        outer += usize::from(rho > big_r);
    }
    // Area of the outer half over the total: 1/2 + r / (pi R).
    let want = 0.5 + r / (std::f64::consts::PI * big_r);
    let got = outer as f64 / s.len() as f64;
    let sd = (want * (1.0 - want) / s.len() as f64).sqrt();
    assert!(
        (got - want).abs() < 5.0 * sd,
        "seed {seed}: outer fraction {got} vs {want}"
    );
}

#[test]
fn hole_plane_hole_is_empty_and_rim_is_sampled() {
    let (seed, side, hole) = (3, 2.0, 0.4);
    let s = scan(&Shape::hole_plane(side, hole), 100_000, 0.0, seed);
    let mut rim = 0usize;
    for (i, (&p, &n)) in s.points.iter().zip(&s.normals).enumerate() {
        assert_eq!(p.z, 0.0, "seed {seed} point {i}");
        assert_eq!(n, DVec3::Z, "seed {seed} point {i}");
        let r = p.truncate().length();
        assert!(r >= hole, "seed {seed} point {i} inside the hole: r = {r}");
        assert!(
            p.x.abs() <= side / 2.0 && p.y.abs() <= side / 2.0,
            "seed {seed} point {i}"
        );
        rim += usize::from(r < hole + 0.05);
    }
    // The annulus just outside the hole has its area's share of the points.
    let pi = std::f64::consts::PI;
    let want = pi * ((hole + 0.05f64).powi(2) - hole * hole) / (side * side - pi * hole * hole);
    let got = rim as f64 / s.len() as f64;
    assert!(
        (got - want).abs() < 5.0 * (want / s.len() as f64).sqrt(),
        "seed {seed}: rim {got} vs {want}"
    );
}

#[test]
fn two_sheets_outward_normals() {
    let (seed, sep) = (4, 0.02);
    let s = scan(&Shape::two_sheets(1.0, sep), 20_000, 0.0, seed);
    let mut upper = 0;
    for (i, (&p, &n)) in s.points.iter().zip(&s.normals).enumerate() {
        assert_eq!(p.z.abs(), sep / 2.0, "seed {seed} point {i}");
        assert_eq!(
            n,
            DVec3::new(0.0, 0.0, p.z.signum()),
            "seed {seed} point {i}"
        );
        upper += usize::from(p.z > 0.0);
    }
    let sd = (s.len() as f64 * 0.25).sqrt();
    assert!(
        (upper as f64 - s.len() as f64 / 2.0).abs() < 5.0 * sd,
        "seed {seed}: {upper}"
    );
}

/// The strip's normal recomputed from `(x_u x x_t)`, written out here
/// independently of the library: `u = 2 theta`, `theta in [0, pi)`.
fn moebius_frame(radius: f64, p: DVec3) -> (f64, f64, DVec3) {
    let u = p.y.atan2(p.x).rem_euclid(2.0 * std::f64::consts::PI);
    let (s, c) = (u / 2.0).sin_cos();
    let (rho, z) = (p.truncate().length() - radius, p.z);
    let off_line = rho * s - z * c;
    let t = rho * c + z * s;
    let a = radius + t * c;
    let xu = DVec3::new(
        -a * u.sin() - t * s / 2.0 * u.cos(),
        a * u.cos() - t * s / 2.0 * u.sin(),
        t * c / 2.0,
    );
    let xt = DVec3::new(c * u.cos(), c * u.sin(), s);
    (off_line, t, xu.cross(xt).normalize())
}

/// Share of the strip's area where `t cos(u/2) > 0` (outside the centre
/// circle), by the midpoint rule.
fn moebius_outer_area_fraction(radius: f64, width: f64) -> f64 {
    let (nu, nt) = (2000, 200);
    let (mut outer, mut total) = (0.0, 0.0);
    for i in 0..nu {
        let c = ((i as f64 + 0.5) / nu as f64 * std::f64::consts::PI).cos();
        for j in 0..nt {
            let t = width * ((j as f64 + 0.5) / nt as f64 - 0.5);
            let da = ((radius + t * c).powi(2) + t * t / 4.0).sqrt();
            total += da;
            if t * c > 0.0 {
                outer += da;
            }
        }
    }
    outer / total
}

#[test]
fn moebius_on_strip_with_continuous_parametric_normals() {
    let (seed, radius, width) = (5, 1.0, 0.5);
    let s = scan(&Shape::moebius(radius, width), 40_000, 0.0, seed);
    let (mut near_zero, mut near_two_pi) = (DVec3::ZERO, DVec3::ZERO);
    let mut outward = 0usize;
    for (i, (&p, &n)) in s.points.iter().zip(&s.normals).enumerate() {
        let (off, t, want) = moebius_frame(radius, p);
        outward += usize::from(p.truncate().length() > radius);
        assert!(
            off.abs() < EPS,
            "seed {seed} point {i}: off the ruling by {off}"
        );
        assert!(
            t.abs() <= width / 2.0 + EPS,
            "seed {seed} point {i}: t = {t}"
        );
        assert_unit(n, seed, i);
        assert_close(n, want, 1e-9, "normal", seed, i);
        if p.x > 0.0 && p.y.abs() < 0.05 {
            *(if p.y > 0.0 {
                &mut near_zero
            } else {
                &mut near_two_pi
            }) += n;
        }
    }
    // Uniform by area: the share beyond the centre circle is its share of
    // the area, with area element sqrt((R + t c)^2 + t^2 / 4).
    let want = moebius_outer_area_fraction(radius, width);
    let got = outward as f64 / s.len() as f64;
    let sd = (want * (1.0 - want) / s.len() as f64).sqrt();
    assert!(
        (got - want).abs() < 5.0 * sd,
        "seed {seed}: outer share {got} vs {want}"
    );
    // Non-orientable: across the seam u = 0 ~ 2 pi the normal field flips.
    let cos = near_zero.normalize().dot(near_two_pi.normalize());
    assert!(
        cos < -0.99,
        "seed {seed}: normals across the seam, cos {cos}"
    );
}

#[test]
fn density_step_is_twenty_to_one_on_a_curved_sheet() {
    let (seed, side, ratio) = (6, 2.0, 20.0);
    let shape = Shape::density_step(side, ratio);
    let Shape::DensityStep { sag, .. } = &shape else {
        unreachable!()
    };
    let n = 210_000;
    let s = scan(&shape, n, 0.0, seed);
    let mut sparse = 0usize;
    for (i, (&p, &nrm)) in s.points.iter().zip(&s.normals).enumerate() {
        let k = *sag * 4.0 / (side * side);
        assert!((p.z - k * p.x * p.x).abs() < EPS, "seed {seed} point {i}");
        assert_unit(nrm, seed, i);
        assert_close(
            nrm,
            DVec3::new(-2.0 * k * p.x, 0.0, 1.0).normalize(),
            EPS,
            "normal",
            seed,
            i,
        );
        sparse += usize::from(p.x >= 0.0);
    }
    // Binomial: sparse ~ n / 21 with sd sqrt(n p q); 5 sd is ratio +- 1.
    let got = (n - sparse) as f64 / sparse as f64;
    assert!(
        (got - ratio).abs() < 1.0,
        "seed {seed}: density ratio {got}"
    );
}

/// Ground area element `sqrt(1 + |grad h|^2)` by central differences of the
/// library's height (an oracle independent of its analytic gradient).
fn fd_slope_factor(t: &Terrain, x: f64, y: f64) -> f64 {
    let d = 1e-5;
    let hx = (t.height(x + d, y).0 - t.height(x - d, y).0) / (2.0 * d);
    let hy = (t.height(x, y + d).0 - t.height(x, y - d).0) / (2.0 * d);
    (1.0 + hx * hx + hy * hy).sqrt()
}

/// `int w(x) dA` over ground strip `x in [x0, x1]`, full y, midpoint rule.
fn strip_weight(t: &Terrain, x0: f64, x1: f64) -> f64 {
    let (nx, ny) = (200, 1000);
    let (dx, dy) = ((x1 - x0) / nx as f64, t.side / ny as f64);
    let mut sum = 0.0;
    for i in 0..nx {
        let x = x0 + (i as f64 + 0.5) * dx;
        for j in 0..ny {
            let y = -t.side / 2.0 + (j as f64 + 0.5) * dy;
            sum += t.density_weight(x) * fd_slope_factor(t, x, y) * dx * dy;
        }
    }
    sum
}

#[derive(Debug, PartialEq)]
enum Part {
    Ground,
    Roof,
    Wall,
}

fn classify(t: &Terrain, p: DVec3, n: DVec3, seed: u64, i: usize) -> Part {
    let inside =
        |b: &Building| p.x >= b.min.x && p.x <= b.max.x && p.y >= b.min.y && p.y <= b.max.y;
    if t.buildings.iter().any(|b| p.z == b.roof && inside(b)) {
        assert_eq!(n, DVec3::Z, "seed {seed} roof point {i}");
        return Part::Roof;
    }
    if n.z == 0.0 {
        let b = t.buildings.iter().find(|b| inside(b));
        let b = b.unwrap_or_else(|| panic!("seed {seed} wall point {i} on no building: {p}"));
        let on_wall = (n == DVec3::X && p.x == b.max.x)
            || (n == DVec3::NEG_X && p.x == b.min.x)
            || (n == DVec3::Y && p.y == b.max.y)
            || (n == DVec3::NEG_Y && p.y == b.min.y);
        assert!(
            on_wall,
            "seed {seed} point {i}: normal {n} is not its wall's outward one"
        );
        assert!(
            p.z >= t.height(p.x, p.y).0 && p.z <= b.roof,
            "seed {seed} wall point {i}"
        );
        return Part::Wall;
    }
    assert!(
        !t.in_footprint(p.x, p.y),
        "seed {seed} ground point {i} under a building"
    );
    assert!(
        (p.z - t.height(p.x, p.y).0).abs() < EPS * t.side,
        "seed {seed} point {i}"
    );
    let d = 1e-5;
    let hx = (t.height(p.x + d, p.y).0 - t.height(p.x - d, p.y).0) / (2.0 * d);
    let hy = (t.height(p.x, p.y + d).0 - t.height(p.x, p.y - d).0) / (2.0 * d);
    assert_close(
        n,
        DVec3::new(-hx, -hy, 1.0).normalize(),
        1e-7,
        "ground normal",
        seed,
        i,
    );
    Part::Ground
}

#[test]
fn steep_terrain_is_uniform_by_area() {
    let seed = 11;
    let terrain = Terrain {
        relief: 40.0,
        density_ratio: 1.0,
        buildings: Vec::new(),
        ..Terrain::city()
    };
    let n = 200_000;
    let s = scan(&Shape::Terrain(terrain.clone()), n, 0.0, seed);
    let total = strip_weight(&terrain, -50.0, 50.0);
    for (x0, x1) in [(-45.0, -30.0), (-20.0, -5.0), (10.0, 25.0), (35.0, 50.0)] {
        let count = s.points.iter().filter(|p| p.x >= x0 && p.x < x1).count();
        let (got, want) = (
            count as f64 / n as f64,
            strip_weight(&terrain, x0, x1) / total,
        );
        let flat = (x1 - x0) / terrain.side;
        let sd = (want * (1.0 - want) / n as f64).sqrt();
        eprintln!("steep terrain strip [{x0}, {x1}): share {got:.4}, area share {want:.4}, flat {flat:.4}");
        assert!(
            (got - want).abs() < 5.0 * sd,
            "seed {seed}: strip [{x0}, {x1}) share {got} vs {want}"
        );
    }
}

#[test]
fn terrain_parts_normals_and_density_gradient() {
    let seed = 7;
    let terrain = Terrain::city();
    let s = scan(&Shape::Terrain(terrain.clone()), 300_000, 0.0, seed);
    let strips = [(-50.0, -40.0), (-5.0, 5.0), (40.0, 50.0)];
    let mut counts = [0usize; 3];
    let mut parts = [0usize; 3];
    for (i, (&p, &n)) in s.points.iter().zip(&s.normals).enumerate() {
        assert_unit(n, seed, i);
        assert!(
            p.x.abs() <= 50.0 && p.y.abs() <= 50.0,
            "seed {seed} point {i}"
        );
        let part = classify(&terrain, p, n, seed, i);
        let ground = part == Part::Ground;
        parts[part as usize] += 1;
        if let Some(k) = strips.iter().position(|&(a, b)| p.x >= a && p.x < b) {
            assert!(ground, "seed {seed} point {i}: strips hold no buildings");
            counts[k] += 1;
        }
    }
    assert!(
        parts.iter().all(|&c| c > 1000),
        "seed {seed}: parts {parts:?}"
    );
    let w: Vec<f64> = strips
        .iter()
        .map(|&(a, b)| strip_weight(&terrain, a, b))
        .collect();
    for k in 1..3 {
        let (want, got) = (w[k] / w[0], counts[k] as f64 / counts[0] as f64);
        eprintln!("terrain strip {k}/0 count ratio {got:.3}, expected {want:.3}");
        let rel_sd = (1.0 / counts[k] as f64 + 1.0 / counts[0] as f64).sqrt();
        assert!(
            (got / want - 1.0).abs() < 5.0 * rel_sd,
            "seed {seed}: strip {k}/0 = {got}, want {want}"
        );
    }
    // The edge strips' per-area density differs by about 10:1 end to end.
    assert!(
        counts[2] as f64 / counts[0] as f64 > 5.0,
        "seed {seed}: {counts:?}"
    );
}

/// Index of the face of `mesh` that contains `p` (on its plane, inside).
fn face_containing(mesh: &TriMesh, p: DVec3) -> Option<usize> {
    (0..mesh.faces.len()).find(|&f| {
        let Some([a, b, c]) = mesh.corners(f) else {
            return false;
        };
        let nrm = (b - a).cross(c - a);
        if nrm.length() == 0.0 || (p - a).dot(nrm.normalize()).abs() > EPS {
            return false;
        }
        [(a, b), (b, c), (c, a)]
            .iter()
            .all(|&(u, v)| (v - u).cross(p - u).dot(nrm) >= -EPS * nrm.length_squared())
    })
}

fn check_mesh_sampling(mesh: &TriMesh, n: usize, seed: u64, chi_limit: f64) {
    let s = scan(&Shape::mesh(mesh.clone()), n, 0.0, seed);
    let mut counts = vec![0usize; mesh.faces.len()];
    let mut in_corner = 0usize;
    for (i, (&p, &nrm)) in s.points.iter().zip(&s.normals).enumerate() {
        let f =
            face_containing(mesh, p).unwrap_or_else(|| panic!("seed {seed} point {i} on no face"));
        let [a, b, c] = mesh.corners(f).unwrap_or_default();
        let cross = (b - a).cross(c - a);
        assert_close(nrm, cross.normalize(), EPS, "face normal", seed, i);
        counts[f] += 1;
        // Barycentric weights; the three corner triangles where one weight
        // exceeds 1/2 cover 3/4 of a triangle.
        let wa = (c - b).cross(p - b).dot(cross) / cross.length_squared();
        let wb = (a - c).cross(p - c).dot(cross) / cross.length_squared();
        let wc = 1.0 - wa - wb;
        in_corner += usize::from(wa.max(wb).max(wc) > 0.5);
    }
    let got = in_corner as f64 / n as f64;
    let sd = (0.75 * 0.25 / n as f64).sqrt();
    assert!(
        (got - 0.75).abs() < 5.0 * sd,
        "seed {seed}: corner share {got} vs 0.75"
    );
    let areas: Vec<f64> = (0..mesh.faces.len()).map(|f| mesh.face_area(f)).collect();
    let total: f64 = areas.iter().sum();
    let (kept_counts, probs): (Vec<usize>, Vec<f64>) = counts
        .iter()
        .zip(&areas)
        .filter(|(&c, &a)| {
            assert!(a > 0.0 || c == 0, "seed {seed}: zero-area face sampled");
            a > 0.0
        })
        .map(|(&c, &a)| (c, a / total))
        .unzip();
    let chi = chi_square(&kept_counts, &probs);
    assert!(
        chi < chi_limit,
        "seed {seed}: face counts chi2 {chi}: {counts:?}"
    );
}

#[test]
fn mesh_samples_stay_on_faces_in_proportion_to_area() {
    // Icosahedron: 20 equal faces, df 19, chi2(0.001) = 43.82.
    check_mesh_sampling(&TriMesh::icosahedron(1.5), 40_000, 8, 43.82);
    // A 1 x 2 x 3 box (unequal faces) plus a zero-area face: df 11 -> 31.26.
    let mut boxy = TriMesh::cube(0.5);
    for v in &mut boxy.vertices {
        *v *= DVec3::new(1.0, 2.0, 3.0);
    }
    boxy.vertices.push(boxy.vertices[0] * 0.5);
    boxy.faces.push([0, 8, 0]);
    check_mesh_sampling(&boxy, 40_000, 9, 31.26);
    // Outward winding of the built-in meshes: normals point away from the centre.
    for mesh in [TriMesh::cube(1.0), TriMesh::icosahedron(1.0)] {
        for f in 0..mesh.faces.len() {
            let [a, b, c] = mesh.corners(f).unwrap_or_default();
            let n = mesh.face_normal(f).unwrap_or_default();
            assert!(n.dot(a + b + c) > 0.0, "face {f} winds inward");
        }
    }
}

#[test]
fn deterministic_per_seed_and_streams_in_chunks() {
    for shape in Shape::presets() {
        let a = scan(&shape, 3000, 0.01, 42);
        let b = scan(&shape, 3000, 0.01, 42);
        let c = scan(&shape, 3000, 0.01, 43);
        assert_eq!(a, b, "{}: seed 42 twice", shape.name());
        assert_ne!(a.points, c.points, "{}: seeds 42 and 43", shape.name());
        let mut st = stream(&shape, 3000, 0.01, 42).unwrap_or_else(|e| panic!("{e}"));
        let (mut pts, mut nrm, mut all) = (Vec::new(), Vec::new(), Scan::default());
        while st.fill(777, &mut pts, &mut nrm) > 0 {
            all.points.extend(&pts);
            all.normals.extend(&nrm);
        }
        assert_eq!(
            a,
            all,
            "{}: chunked stream differs from generate",
            shape.name()
        );
    }
}

#[test]
fn noise_is_isotropic_gaussian_around_the_clean_points() {
    let (seed, sigma, n) = (10, 0.01, 30_000);
    let shape = Shape::unit_sphere();
    let clean = scan(&shape, n, 0.0, seed);
    let noisy = scan(&shape, n, sigma, seed);
    assert_eq!(
        clean.normals, noisy.normals,
        "seed {seed}: noise changed normals"
    );
    let (mut sum, mut sq) = (DVec3::ZERO, DVec3::ZERO);
    for (i, (c, p)) in clean.points.iter().zip(&noisy.points).enumerate() {
        let d = *p - *c;
        assert!(
            d.abs().max_element() < 6.0 * sigma,
            "seed {seed} point {i}: offset {d}"
        );
        sum += d;
        sq += d * d;
    }
    let other = scan(&shape, n, sigma, seed + 1);
    let other_clean = scan(&shape, n, 0.0, seed + 1);
    let shift = |s: &Scan, c: &Scan| s.points[0] - c.points[0];
    let same = (shift(&noisy, &clean) - shift(&other, &other_clean)).length() < 1e-9;
    assert!(!same, "seed {seed}: the noise does not depend on the seed");
    let (mean, var) = (sum / n as f64, sq / n as f64);
    assert!(
        mean.abs().max_element() < 5.0 * sigma / (n as f64).sqrt(),
        "seed {seed}: mean {mean}"
    );
    let want = sigma * sigma;
    assert!(
        (var / want - DVec3::ONE).abs().max_element() < 0.05,
        "seed {seed}: var {var}"
    );
}

/// Mean distance to the nearest other point, by brute force.
fn mean_nn_distance(points: &[DVec3]) -> f64 {
    let total: f64 = points
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let nn = points
                .iter()
                .enumerate()
                .filter(|&(j, _)| j != i)
                .map(|(_, q)| p.distance_squared(*q))
                .fold(f64::INFINITY, f64::min);
            nn.sqrt()
        })
        .sum();
    total / points.len() as f64
}

#[test]
fn spacing_hint_matches_brute_force() {
    let n = 4000;
    let cases = [
        (Shape::unit_sphere(), 0.05),
        (Shape::torus(1.0, 0.3), 0.05),
        (Shape::density_step(2.0, 20.0), 0.10),
        (Shape::mesh(TriMesh::icosahedron(1.0)), 0.05),
    ];
    for (seed, (shape, tol)) in cases.into_iter().enumerate() {
        let hint = mean_spacing_hint(&shape, n).unwrap_or_else(|e| panic!("{e}"));
        let got = mean_nn_distance(&scan(&shape, n, 0.0, seed as u64).points);
        let rel = got / hint - 1.0;
        eprintln!(
            "{}: brute-force mean spacing / hint - 1 = {rel:+.4}",
            shape.name()
        );
        assert!(
            rel.abs() < tol,
            "seed {seed} {}: brute {got} vs hint {hint}",
            shape.name()
        );
    }
    assert_eq!(
        mean_spacing_hint(&Shape::unit_sphere(), 0),
        Ok(f64::INFINITY)
    );
}

#[test]
fn bad_parameters_are_errors_not_panics() {
    let nan = f64::NAN;
    let bad = [
        Shape::sphere(DVec3::ZERO, -1.0),
        Shape::sphere(DVec3::splat(nan), 1.0),
        Shape::torus(1.0, 1.5),
        Shape::hole_plane(1.0, 0.5),
        Shape::two_sheets(1.0, 0.0),
        Shape::moebius(1.0, 1.0),
        Shape::density_step(2.0, 0.5),
        Shape::mesh(TriMesh {
            vertices: vec![DVec3::ZERO; 3],
            faces: vec![[0, 1, 3]],
        }),
        Shape::mesh(TriMesh {
            vertices: vec![DVec3::ZERO; 3],
            faces: vec![[0, 1, 2]],
        }),
        Shape::mesh(TriMesh::default()),
    ];
    for shape in &bad {
        assert!(generate(shape, 10, 0.0, 0).is_err(), "{shape:?} accepted");
    }
    assert_eq!(
        generate(&Shape::unit_sphere(), 1, -1.0, 0),
        Err(SynthError::BadNoise(-1.0))
    );
    let mut t = Terrain::city();
    t.buildings.push(Building {
        min: DVec2::new(-29.0, -19.0),
        max: DVec2::new(-20.0, -10.0),
        roof: 9.0,
    });
    assert!(matches!(
        generate(&Shape::Terrain(t), 1, 0.0, 0),
        Err(SynthError::BadBuilding { index: 3, .. })
    ));
    let mut t = Terrain::city();
    t.buildings[0].roof = 1.0;
    assert!(matches!(
        generate(&Shape::Terrain(t), 1, 0.0, 0),
        Err(SynthError::BadBuilding { index: 0, .. })
    ));
}
