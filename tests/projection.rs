//! Paper 2's local-projection triangulation on generated surfaces: the
//! mesh is manifold, consistently wound, free of self-intersections, keeps
//! sampling holes open, closes closed surfaces, and does not depend on the
//! thread count.

use glam::DVec3;
use scanmesh::mesh::{quality, self_intersections, Mesh};
use scanmesh::recon::projection::{triangulate_points, ProjectionParams};
use scanmesh::synth::{generate, mean_spacing_hint, Shape};

fn mesh_of(shape: &Shape, n: usize, noise_spacing: f64, seed: u64) -> Mesh {
    let spacing = mean_spacing_hint(shape, n).expect("spacing");
    let scan = generate(shape, n, noise_spacing * spacing, seed).expect("scan");
    let (triangles, _) =
        triangulate_points(&scan.points, &ProjectionParams::default()).expect("triangulate");
    Mesh::new(scan.points, triangles)
}

fn signed_volume(m: &Mesh) -> f64 {
    m.triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| m.vertices[i as usize]);
            a.dot(b.cross(c)) / 6.0
        })
        .sum()
}

/// What every output must be: edge-manifold, consistently wound, no
/// self-intersection, no degenerate or duplicate triangle.
fn assert_sound(m: &Mesh, what: &str) {
    let q = quality(m);
    assert_eq!(q.non_manifold_edges, 0, "{what}: {q:?}");
    assert_eq!(q.inconsistent_edges, 0, "{what}");
    assert_eq!(q.duplicate_triangles, 0, "{what}");
    assert_eq!(q.repeated_index_triangles, 0, "{what}");
    assert_eq!(self_intersections(m).pairs, 0, "{what}");
}

#[test]
fn a_sphere_closes_into_one_outward_piece() {
    let m = mesh_of(&Shape::unit_sphere(), 6000, 0.0, 3);
    assert_sound(&m, "sphere");
    let q = quality(&m);
    assert_eq!(q.components, 1);
    assert!(q.boundary_loops <= 2, "{} loops", q.boundary_loops);
    // Nearly all of the sphere's area, wound outward.
    let v = signed_volume(&m);
    let full = 4.0 / 3.0 * std::f64::consts::PI;
    assert!(v > 0.97 * full && v <= full, "volume {v} of {full}");
    assert!(q.total_area > 0.97 * 4.0 * std::f64::consts::PI);
}

#[test]
fn a_sampling_hole_stays_open() {
    // A unit square with a hole of radius 0.25: the outer loop and the one
    // around the hole (the growth may leave one more small hole where its
    // fronts meet, here one of 4 edges among 202).
    let m = mesh_of(&Shape::hole_plane(1.0, 0.25), 8000, 0.05, 5);
    assert_sound(&m, "hole plane");
    let q = quality(&m);
    assert_eq!(q.components, 1);
    assert!((2..=3).contains(&q.boundary_loops), "{q:?}");
    let hole_area = std::f64::consts::PI * 0.25 * 0.25;
    assert!(
        q.total_area < 1.0 - 0.9 * hole_area,
        "area {}",
        q.total_area
    );
    assert!(
        q.total_area > 0.95 * (1.0 - hole_area),
        "area {}",
        q.total_area
    );
}

#[test]
fn a_moebius_strip_is_wound_consistently_by_leaving_a_seam() {
    // Non-orientable: the directed-edge rule refuses the triangles that
    // would close the strip with opposite windings.
    let m = mesh_of(&Shape::moebius(1.0, 0.5), 8000, 0.0, 7);
    assert_sound(&m, "moebius");
    assert!(quality(&m).orientable);
}

#[test]
fn noisy_torus_is_sound_and_threads_do_not_matter() {
    let shape = Shape::torus(1.0, 0.3);
    let spacing = mean_spacing_hint(&shape, 8000).expect("spacing");
    let scan = generate(&shape, 8000, 0.1 * spacing, 11).expect("scan");
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool");
        pool.install(|| triangulate_points(&scan.points, &ProjectionParams::default()))
            .expect("triangulate")
            .0
    };
    let one = run(1);
    assert_eq!(one, run(2));
    let m = Mesh::new(scan.points.clone(), one);
    assert_sound(&m, "torus");
    assert_eq!(quality(&m).components, 1);
}

#[test]
fn duplicate_points_never_make_degenerate_triangles() {
    let shape = Shape::unit_sphere();
    let mut points = generate(&shape, 3000, 0.0, 13).expect("scan").points;
    let copies: Vec<DVec3> = points.iter().step_by(3).copied().collect();
    points.extend(copies);
    let (triangles, _) =
        triangulate_points(&points, &ProjectionParams::default()).expect("triangulate");
    let m = Mesh::new(points, triangles);
    assert_sound(&m, "duplicates");
    assert_eq!(quality(&m).zero_area_triangles, 0);
}

#[test]
fn projection_parameters_out_of_range_are_refused_by_name() {
    let d = ProjectionParams::default();
    for (bad, name) in [
        (ProjectionParams { k: 0, ..d }, "k"),
        (
            ProjectionParams {
                thin: f64::NAN,
                ..d
            },
            "thin",
        ),
        (ProjectionParams { thin: -0.1, ..d }, "thin"),
        (ProjectionParams { max_edge: 0.0, ..d }, "max_edge"),
        (
            ProjectionParams {
                max_edge: f64::NAN,
                ..d
            },
            "max_edge",
        ),
        (
            ProjectionParams {
                max_angle_deg: f64::NAN,
                ..d
            },
            "max_angle_deg",
        ),
    ] {
        let e = bad.validate().expect_err("accepted");
        assert_eq!(e.name, name, "{e}");
    }
    assert!(d.validate().is_ok());
}
