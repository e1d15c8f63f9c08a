//! Quality and topology metrics on hand-built meshes with known answers,
//! procedural surfaces with known Euler characteristic and genus, and
//! invariance under relabelling.

use glam::{DVec2, DVec3};
use scanmesh::mesh::shapes::moebius;
use scanmesh::mesh::{quality, shapes, Mesh, QualityReport};

fn v(x: f64, y: f64, z: f64) -> DVec3 {
    DVec3::new(x, y, z)
}

fn tetrahedron() -> Mesh {
    Mesh::new(
        vec![v(0., 0., 0.), v(1., 0., 0.), v(0., 1., 0.), v(0., 0., 1.)],
        vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
    )
}

fn cube() -> Mesh {
    let vertices = (0..8)
        .map(|i| v((i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64))
        .collect();
    // Each face as a quad (a, b, c, d) counter-clockwise seen from outside.
    let quads = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    let triangles = quads
        .iter()
        .flat_map(|&[a, b, c, d]| [[a, b, c], [a, c, d]])
        .collect();
    Mesh::new(vertices, triangles)
}

/// Signed volume (divergence theorem): positive for outward orientation.
fn signed_volume(m: &Mesh) -> f64 {
    m.triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| m.vertices[i as usize]);
            a.dot(b.cross(c)) / 6.0
        })
        .sum()
}

/// Checks the invariants every report must satisfy, whatever the mesh.
fn consistent(r: &QualityReport) {
    let chi = r.referenced_vertices as i64 - r.edges as i64 + r.topological_triangles as i64;
    assert_eq!(r.euler_characteristic, chi);
    assert_eq!(r.vertices, r.referenced_vertices + r.unreferenced_vertices);
    assert_eq!(r.components as usize, r.component_details.len());
    assert_eq!(r.consistently_oriented, r.inconsistent_edges == 0);
    let half_edges = 3 * r.topological_triangles;
    assert!(
        half_edges >= r.boundary_edges + 2 * (r.edges - r.boundary_edges - r.non_manifold_edges)
    );
}

fn report(m: &Mesh) -> QualityReport {
    let r = quality(m);
    consistent(&r);
    r
}

#[test]
fn tetrahedron_is_a_closed_sphere() {
    let m = tetrahedron();
    assert!(signed_volume(&m) > 0.0);
    let r = report(&m);
    assert_eq!(
        (r.referenced_vertices, r.edges, r.topological_triangles),
        (4, 6, 4)
    );
    assert_eq!(r.euler_characteristic, 2);
    assert!(r.watertight && r.consistently_oriented && r.orientable);
    assert_eq!((r.boundary_edges, r.boundary_loops), (0, 0));
    assert_eq!(r.genus, Some(0));
    assert!((r.total_area - (1.5 + 3f64.sqrt() / 2.0)).abs() < 1e-15);
}

#[test]
fn cube_of_twelve_triangles() {
    let m = cube();
    assert!((signed_volume(&m) - 1.0).abs() < 1e-15);
    let r = report(&m);
    assert_eq!(
        (r.referenced_vertices, r.edges, r.topological_triangles),
        (8, 18, 12)
    );
    assert_eq!(r.euler_characteristic, 2);
    assert!(r.watertight && r.consistently_oriented);
    assert_eq!(r.genus, Some(0));
    assert_eq!(r.total_area, 6.0);
    assert_eq!((r.non_manifold_edges, r.non_manifold_vertices), (0, 0));
}

#[test]
fn open_square_has_one_boundary_loop() {
    let m = shapes::grid(1, 1, DVec2::ONE);
    let r = report(&m);
    assert_eq!((r.boundary_edges, r.boundary_loops), (4, 1));
    assert_eq!(r.euler_characteristic, 1);
    assert!(!r.watertight);
    assert_eq!(r.genus, None);
    assert_eq!(r.total_area, 1.0);
}

/// A 3x3 grid of cells without the middle one.
fn square_with_hole() -> Mesh {
    let mut m = shapes::grid(3, 3, DVec2::splat(3.0));
    // Cell (i, j) holds triangles 2 * (3 j + i) and the next one.
    let hole = 2 * (3 + 1);
    m.triangles.drain(hole..hole + 2);
    m
}

#[test]
fn square_with_square_hole_has_two_loops() {
    let r = report(&square_with_hole());
    assert_eq!((r.boundary_edges, r.boundary_loops), (12 + 4, 2));
    assert_eq!(r.euler_characteristic, 0);
    assert_eq!(r.non_manifold_vertices, 0);
    assert_eq!(r.total_area, 8.0);
}

#[test]
fn two_tetrahedra_sharing_a_vertex_make_a_non_manifold_vertex() {
    let mut m = tetrahedron();
    let shift = v(1.0, 1.0, 1.0);
    m.vertices
        .extend([v(1., 0., 0.), v(0., 1., 0.), v(0., 0., 1.)].map(|p| p + shift));
    // Second tetrahedron: vertex 3 plus 4, 5, 6 (same shape, apex shared).
    m.triangles
        .extend([[3, 5, 4], [3, 4, 6], [3, 6, 5], [4, 5, 6]]);
    let r = report(&m);
    assert_eq!(r.components, 1);
    assert_eq!((r.non_manifold_vertices, r.non_manifold_edges), (1, 0));
    assert_eq!(r.euler_characteristic, 7 - 12 + 8);
    assert!(r.watertight, "no boundary and no non-manifold edge");
    assert!(!r.component_details[0].closed);
    assert_eq!(r.genus, None);
}

#[test]
fn three_triangles_on_one_edge_make_a_non_manifold_edge() {
    let m = Mesh::new(
        vec![
            v(0., 0., 0.),
            v(1., 0., 0.),
            v(0., 1., 0.),
            v(0., -1., 0.),
            v(0., 0., 1.),
        ],
        vec![[0, 1, 2], [1, 0, 3], [0, 1, 4]],
    );
    let r = report(&m);
    assert_eq!((r.edges, r.non_manifold_edges, r.boundary_edges), (7, 1, 6));
    assert!(!r.watertight);
    // The three fans at each end are joined through the shared edge.
    assert_eq!(r.non_manifold_vertices, 0);
    assert_eq!(r.inconsistent_edges, 0, "non-manifold edges are not judged");
}

#[test]
fn flipped_triangle_is_an_orientation_inconsistency() {
    let mut m = tetrahedron();
    m.triangles[3] = [1, 3, 2];
    let r = report(&m);
    assert_eq!(r.inconsistent_edges, 3);
    assert!(!r.consistently_oriented);
    assert!(r.orientable, "flipping one triangle back repairs it");
    assert!(r.watertight);
    assert_eq!(r.genus, None);
}

#[test]
fn duplicate_and_degenerate_triangles_are_counted() {
    let mut m = shapes::grid(1, 1, DVec2::ONE);
    assert_eq!(m.triangles, [[0, 1, 3], [0, 3, 2]]);
    m.vertices
        .extend([v(5., 0., 0.), v(6., 0., 0.), v(7., 0., 0.)]);
    m.triangles
        .extend([[3, 1, 0], [0, 0, 1], [4, 5, 6], [2, 0, 3]]);
    let r = report(&m);
    assert_eq!(
        r.duplicate_triangles, 2,
        "[3,1,0] repeats [0,1,3], [2,0,3] repeats [0,3,2]"
    );
    assert_eq!((r.repeated_index_triangles, r.zero_area_triangles), (1, 1));
    assert_eq!(r.degenerate_triangles, 2);
    assert_eq!(
        r.topological_triangles, 5,
        "the repeated-index triangle is left out"
    );
    assert_eq!(
        r.components, 2,
        "the collinear triangle is its own component"
    );
}

#[test]
fn torus_has_euler_characteristic_zero_and_genus_one() {
    for (nu, nv) in [(3, 3), (8, 5), (40, 17)] {
        let m = shapes::torus(2.0, 0.5, nu, nv);
        let r = report(&m);
        assert_eq!(r.euler_characteristic, 0, "{nu}x{nv}");
        assert_eq!(r.genus, Some(1), "{nu}x{nv}");
        assert!(r.watertight && r.consistently_oriented, "{nu}x{nv}");
        assert!(signed_volume(&m) > 0.0, "outward orientation {nu}x{nv}");
    }
}

#[test]
fn icosphere_is_genus_zero_at_every_level() {
    for level in 0..4 {
        let m = shapes::icosphere(level);
        let r = report(&m);
        assert_eq!(r.topological_triangles, 20 * 4u64.pow(level));
        assert_eq!(r.genus, Some(0), "level {level}");
        assert!(signed_volume(&m) > 0.0);
        let exact = 4.0 * std::f64::consts::PI;
        assert!(r.total_area < exact, "inscribed polyhedron has less area");
    }
}

#[test]
fn moebius_strip_is_non_orientable_with_one_boundary_loop() {
    for n in [3, 12, 31] {
        let r = report(&moebius(n));
        assert_eq!(r.euler_characteristic, 0);
        assert_eq!(
            (r.boundary_edges, r.boundary_loops),
            (2 * n as u64, 1),
            "n {n}"
        );
        assert!(!r.orientable && !r.consistently_oriented, "n {n}");
        assert!(r.inconsistent_edges >= 1);
        assert_eq!((r.non_manifold_edges, r.non_manifold_vertices), (0, 0));
    }
}

#[test]
fn bow_tie_of_two_triangles_has_two_loops() {
    // Naive chaining by "the boundary edge leaving this vertex" is ambiguous
    // at vertex 0; each fan must close its own loop.
    let m = Mesh::new(
        vec![
            v(0., 0., 0.),
            v(1., 0., 0.),
            v(1., 1., 0.),
            v(-1., 0., 0.),
            v(-1., -1., 0.),
        ],
        vec![[0, 1, 2], [0, 3, 4]],
    );
    let r = report(&m);
    assert_eq!(
        (r.boundary_edges, r.boundary_loops, r.non_manifold_vertices),
        (6, 2, 1)
    );
    assert_eq!(r.components, 1);
}

#[test]
fn holes_touching_at_a_vertex_merge_into_one_loop() {
    // 4x4 cells without cells (1,1) and (2,2), which touch at vertex (2,2).
    // Split that vertex per fan and the two holes become one: outer + 1.
    let mut m = shapes::grid(4, 4, DVec2::splat(4.0));
    let cell = |i: usize, j: usize| 2 * (4 * j + i);
    let (a, b) = (cell(1, 1), cell(2, 2));
    m.triangles.drain(b..b + 2);
    m.triangles.drain(a..a + 2);
    let r = report(&m);
    assert_eq!((r.boundary_edges, r.boundary_loops), (16 + 8, 2));
    assert_eq!(r.non_manifold_vertices, 1);
    // Two loops, and the other counts agree with splitting vertex (2,2): chi
    // of a disc with one hole is 0, one vertex fewer before the split.
    assert_eq!(r.euler_characteristic, -1);
}

#[test]
fn unreferenced_and_invalid_data_is_counted_not_fatal() {
    let mut m = tetrahedron();
    m.vertices.push(v(9., 9., 9.));
    m.vertices.push(v(f64::NAN, 0., 0.));
    m.triangles.push([0, 1, 99]);
    m.triangles.push([0, 1, 5]);
    let r = report(&m);
    assert_eq!(r.invalid_triangles, 2);
    assert_eq!(r.unreferenced_vertices, 2);
    assert_eq!(r.genus, Some(0));
    assert!(m.validate().is_err());
}

#[test]
fn components_get_their_own_genus() {
    let torus = shapes::torus(3.0, 1.0, 9, 6);
    let mut m = tetrahedron();
    let offset = m.vertices.len() as u32;
    m.vertices.extend(&torus.vertices);
    m.triangles
        .extend(torus.triangles.iter().map(|t| t.map(|i| i + offset)));
    let r = report(&m);
    assert_eq!(r.components, 2);
    let genera: Vec<_> = r.component_details.iter().map(|c| c.genus).collect();
    assert_eq!(genera, [Some(0), Some(1)]);
    assert_eq!(r.genus, None, "overall genus needs one component");
    assert_eq!(r.euler_characteristic, 2);
}

/// Seeded permutation (SplitMix64-driven Fisher-Yates).
fn permutation(n: usize, seed: u64) -> Vec<usize> {
    let mut state = seed;
    let mut next = || {
        state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    };
    let mut p: Vec<usize> = (0..n).collect();
    for i in (1..n).rev() {
        p.swap(i, (next() % (i as u64 + 1)) as usize);
    }
    p
}

#[test]
fn counts_do_not_depend_on_labels_or_order() {
    let base = moebius(20);
    let want = quality(&base);
    for seed in 1..6u64 {
        let vp = permutation(base.vertices.len(), seed);
        let tp = permutation(base.triangles.len(), seed ^ 0xABCD);
        let mut vertices = vec![DVec3::ZERO; base.vertices.len()];
        for (old, &new) in vp.iter().enumerate() {
            vertices[new] = base.vertices[old];
        }
        let triangles = tp
            .iter()
            .map(|&t| base.triangles[t].map(|i| vp[i as usize] as u32))
            .collect();
        let got = report(&Mesh::new(vertices, triangles));
        let key = |r: &QualityReport| {
            (
                r.edges,
                r.boundary_edges,
                r.boundary_loops,
                r.euler_characteristic,
                r.orientable,
            )
        };
        assert_eq!(key(&got), key(&want), "seed {seed}");
        assert!(
            (got.total_area - want.total_area).abs() < 1e-12,
            "seed {seed}"
        );
    }
}

#[test]
fn report_serialises_and_prints() {
    let r = quality(&cube());
    let json = serde_json::to_value(&r).unwrap();
    assert_eq!(json["euler_characteristic"], 2);
    assert_eq!(json["genus"], 0);
    let text = r.to_string();
    assert!(text.contains("euler char.       2"), "{text}");
    assert!(text.contains("watertight        yes"), "{text}");
}

#[path = "mesh_quality/distance.rs"]
mod distance;
#[path = "mesh_quality/triangles.rs"]
mod triangles;
