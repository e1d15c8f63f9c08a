//! Self-intersecting pairs and smallest angles with known answers, and the
//! exact pair test against an independent separating-axis oracle.

use glam::{DVec2, DVec3};
use scanmesh::mesh::angles::min_angle_deg;
use scanmesh::mesh::{angle_report, self_intersections, shapes, Mesh};

fn v(x: f64, y: f64, z: f64) -> DVec3 {
    DVec3::new(x, y, z)
}

#[test]
fn closed_and_flat_meshes_do_not_self_intersect() {
    for m in [
        shapes::icosphere(3),
        shapes::torus(1.0, 0.3, 40, 16),
        shapes::grid(12, 9, DVec2::new(3.0, 2.0)),
    ] {
        let r = self_intersections(&m);
        assert_eq!((r.pairs, r.triangles_skipped), (0, 0), "{r:?}");
        assert_eq!(r.triangles_tested, m.triangles.len() as u64);
    }
}

/// A vertical blade through the interior of one grid triangle (cell (0,0)
/// splits into a = (0,0), b = (1,0), c = (1,1) and a, c, d; the blade
/// crosses z = 0 at y = 0.2, x in [0.625, 0.675], below the diagonal).
#[test]
fn a_blade_through_a_grid_is_one_pair() {
    let mut m = shapes::grid(4, 4, DVec2::new(4.0, 4.0));
    let first = m.vertices.len() as u32;
    m.vertices
        .extend([v(0.6, 0.2, -1.), v(0.7, 0.2, -1.), v(0.65, 0.2, 1.)]);
    m.triangles.push([first, first + 1, first + 2]);
    let r = self_intersections(&m);
    assert_eq!(r.pairs, 1);
    assert_eq!(r.triangles_involved, 2);
    assert_eq!(r.first_pairs, vec![[0, 32]]);
    // Folding one grid triangle onto its neighbour across their shared
    // edge (the diagonal of cell (0,0)) adds exactly one pair.
    let mut folded = shapes::grid(1, 1, DVec2::new(1.0, 1.0));
    folded.vertices[2] = v(0.9, 0.1, 0.0); // (0, 1) moves across the diagonal 0-3
    assert_eq!(self_intersections(&folded).pairs, 1);
}

#[test]
fn shared_vertices_only_count_real_contact() {
    // A fan of six triangles around the origin, flat: no pair meets beyond
    // its shared vertex or edge.
    let mut verts = vec![DVec3::ZERO];
    for i in 0..6 {
        let a = std::f64::consts::TAU * i as f64 / 6.0;
        verts.push(v(a.cos(), a.sin(), 0.0));
    }
    let fan: Vec<[u32; 3]> = (0..6).map(|i| [0, 1 + i, 1 + (i + 1) % 6]).collect();
    let m = Mesh::new(verts.clone(), fan.clone());
    assert_eq!(self_intersections(&m).pairs, 0);
    // A seventh triangle on vertex 0, tilted through the plane: it meets
    // the fan along a segment from 0 at 45 degrees, inside triangle 0
    // only. An eighth, above the plane but for vertex 0: no contact.
    verts.extend([v(0.8, 0.3, 0.5), v(0.3, 0.8, -0.5)]);
    verts.extend([v(0.5, 0.2, 0.5), v(0.2, 0.5, 0.5)]);
    let mut tris = fan;
    tris.extend([[0, 7, 8], [0, 9, 10]]);
    let r = self_intersections(&Mesh::new(verts, tris));
    assert_eq!(r.pairs, 1, "{r:?}");
    assert_eq!(r.first_pairs, vec![[0, 6]]);
}

#[test]
fn flat_and_invalid_triangles_are_left_out() {
    let m = Mesh::new(
        vec![v(0., 0., 0.), v(1., 0., 0.), v(2., 0., 0.), v(0., 1., 0.)],
        vec![[0, 1, 2], [0, 0, 3], [0, 1, 9], [0, 1, 3]],
    );
    let r = self_intersections(&m);
    assert_eq!(
        (r.triangles_tested, r.triangles_skipped, r.pairs),
        (1, 3, 0)
    );
}

/// Separating-axis oracle for two triangles in general position: disjoint
/// iff the face normals or an edge-edge cross product separate them.
fn sat_disjoint(p: &[DVec3; 3], q: &[DVec3; 3]) -> bool {
    let edges = |t: &[DVec3; 3]| [t[1] - t[0], t[2] - t[1], t[0] - t[2]];
    let mut axes = vec![
        (p[1] - p[0]).cross(p[2] - p[0]),
        (q[1] - q[0]).cross(q[2] - q[0]),
    ];
    for e in edges(p) {
        for f in edges(q) {
            axes.push(e.cross(f));
        }
    }
    axes.iter().any(|a| {
        let span = |t: &[DVec3; 3]| {
            let d = t.map(|x| x.dot(*a));
            (d[0].min(d[1]).min(d[2]), d[0].max(d[1]).max(d[2]))
        };
        let ((p0, p1), (q0, q1)) = (span(p), span(q));
        p1 < q0 || q1 < p0
    })
}

#[test]
fn random_pairs_agree_with_the_separating_axis_oracle() {
    let seed = 0x7131u64;
    let mut s = seed;
    let mut next = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut verts = Vec::new();
    let mut tris = Vec::new();
    for t in 0..400u32 {
        let centre = v(next(), next(), next()) * 3.0;
        for _ in 0..3 {
            verts.push(centre + v(next() - 0.5, next() - 0.5, next() - 0.5));
        }
        tris.push([3 * t, 3 * t + 1, 3 * t + 2]);
    }
    let m = Mesh::new(verts, tris);
    let corners = |t: usize| m.corners(m.triangles[t]).unwrap();
    let mut expected = 0;
    for i in 0..m.triangles.len() {
        for j in i + 1..m.triangles.len() {
            expected += u64::from(!sat_disjoint(&corners(i), &corners(j)));
        }
    }
    assert!(expected > 50, "seed {seed:#x}: too few crossings to test");
    assert_eq!(self_intersections(&m).pairs, expected, "seed {seed:#x}");
}

#[test]
fn smallest_angles_have_known_values() {
    let equilateral = [v(0., 0., 0.), v(1., 0., 0.), v(0.5, 3f64.sqrt() / 2., 0.)];
    assert!((min_angle_deg(equilateral[0], equilateral[1], equilateral[2]) - 60.0).abs() < 1e-9);
    let sliver = [v(0., 0., 0.), v(1., 0., 0.), v(1., 0.1, 0.)];
    let expected = 0.1f64.atan().to_degrees();
    assert!((min_angle_deg(sliver[0], sliver[1], sliver[2]) - expected).abs() < 1e-9);
    let m = Mesh::new(
        [equilateral, sliver].concat(),
        vec![[0, 1, 2], [3, 4, 5], [3, 3, 4]],
    );
    let r = angle_report(&m);
    assert_eq!(r.triangles, 2, "the repeated-index triangle has no angles");
    assert_eq!(r.min_angle_histogram[11], 1);
    assert_eq!(r.min_angle_histogram[1], 1);
    assert_eq!((r.slivers, r.sliver_share), (1, 0.5));
    assert!((r.mean_min_angle_deg - (60.0 + expected) / 2.0).abs() < 1e-9);
    assert!((r.smallest_angle_deg.unwrap() - expected).abs() < 1e-9);
    // A grid of right isosceles triangles: every smallest angle is 45.
    let g = angle_report(&shapes::grid(8, 8, DVec2::new(1.0, 1.0)));
    assert_eq!(
        (g.triangles, g.min_angle_histogram[9], g.slivers),
        (128, 128, 0)
    );
}
