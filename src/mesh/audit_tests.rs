//! The streaming audit against `quality` (the in-memory oracle) on shapes
//! of known topology, on seeded random meshes, and against itself with
//! buffers so small that hundreds of runs are merged in rounds.

use super::*;
use crate::mesh::audit_mesh::audit_mesh_sized;
use crate::mesh::quality::quality;
use crate::mesh::shapes::{grid, icosphere, torus};
use crate::mesh::union_find::DisjointSets;
use crate::mesh::write::MeshWriter;
use crate::mesh::MeshFormat;
use crate::mesh::{Mesh, MeshError};
use crate::rng::Rng;
use glam::DVec2;

/// Buffers small enough that every mesh below spills hundreds of runs
/// (two triangles a run) and merges them three at a time, in rounds, with
/// one page of each cache.
const TINY: Sizes = Sizes {
    runs: RunSizes {
        chunk_bytes: 7 * 12,
        fan_in: 3,
        merge_bytes: 64,
    },
    cache_bytes: 1,
};

fn audit(mesh: &Mesh, sizes: Sizes) -> MeshAudit {
    let dir = tempfile::tempdir().unwrap();
    let a = audit_mesh_sized(mesh, dir.path(), sizes).unwrap();
    // Every scratch file is unnamed: nothing is left behind.
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    a
}

/// Six times the signed volume of each closed component, by the component's
/// smallest vertex, summed in memory in the audit's frame (the first
/// vertex).
fn volumes(mesh: &Mesh) -> Vec<(u32, f64)> {
    let q = quality(mesh);
    let mut sets = DisjointSets::<u32>::new(mesh.vertices.len());
    let topological = |t: &&[u32; 3]| t[0] != t[1] && t[1] != t[2] && t[0] != t[2];
    for t in mesh.triangles.iter().filter(topological) {
        sets.union(t[0] as usize, t[1] as usize);
        sets.union(t[0] as usize, t[2] as usize);
    }
    let o = mesh.vertices.first().copied().unwrap_or_default();
    let mut out = Vec::new();
    for c in q.component_details.iter().filter(|c| c.closed) {
        let root = sets.find(c.first_vertex as usize);
        let six: f64 = mesh
            .triangles
            .iter()
            .filter(topological)
            .filter(|t| sets.find(t[0] as usize) == root)
            .map(|t| {
                let [a, b, c] = t.map(|i| mesh.vertices[i as usize] - o);
                a.dot(b.cross(c))
            })
            .sum();
        out.push((c.first_vertex, six / 6.0));
    }
    out
}

/// Components of the boundary-edge graph (the audit's loops), in memory.
fn boundary_components(mesh: &Mesh) -> u64 {
    let mut edges: Vec<(u32, u32)> = Vec::new();
    for t in &mesh.triangles {
        if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
            continue;
        }
        for i in 0..3 {
            let (a, b) = (t[i], t[(i + 1) % 3]);
            edges.push((a.min(b), a.max(b)));
        }
    }
    edges.sort_unstable();
    let boundary: Vec<(u32, u32)> = edges
        .chunk_by(|x, y| x == y)
        .filter(|g| g.len() == 1)
        .map(|g| g[0])
        .collect();
    let mut sets = DisjointSets::<u32>::new(mesh.vertices.len());
    let mut on = vec![false; mesh.vertices.len()];
    for &(a, b) in &boundary {
        sets.union(a as usize, b as usize);
        on[a as usize] = true;
        on[b as usize] = true;
    }
    (0..mesh.vertices.len())
        .filter(|&v| on[v] && sets.find(v) == v)
        .count() as u64
}

/// The audit of `mesh` equals `quality`'s counts, field by field, and its
/// volumes the in-memory sums; returns it.
fn check(mesh: &Mesh, what: &str) -> MeshAudit {
    let a = audit(mesh, Sizes::DEFAULT);
    let q = quality(mesh);
    let closed = q.component_details.iter().filter(|c| c.closed).count() as u64;
    assert_eq!(a.vertices, q.vertices, "{what}: vertices");
    assert_eq!(a.triangles, q.triangles, "{what}: triangles");
    assert_eq!(
        a.referenced_vertices, q.referenced_vertices,
        "{what}: referenced"
    );
    assert_eq!(
        a.repeated_index_triangles, q.repeated_index_triangles,
        "{what}: repeated"
    );
    assert_eq!(
        a.triangles - a.repeated_index_triangles,
        q.topological_triangles,
        "{what}: topological"
    );
    assert_eq!(a.edges, q.edges, "{what}: edges");
    assert_eq!(a.boundary_edges, q.boundary_edges, "{what}: boundary");
    assert_eq!(
        a.non_manifold_edges, q.non_manifold_edges,
        "{what}: nm edges"
    );
    assert_eq!(
        a.non_manifold_vertices, q.non_manifold_vertices,
        "{what}: nm vertices"
    );
    assert_eq!(
        a.inconsistent_edges, q.inconsistent_edges,
        "{what}: inconsistent"
    );
    assert_eq!(a.components, q.components, "{what}: components");
    assert_eq!(a.closed_components, closed, "{what}: closed");
    assert_eq!(
        a.euler_characteristic, q.euler_characteristic,
        "{what}: euler"
    );
    assert_eq!(
        a.boundary_loops,
        boundary_components(mesh),
        "{what}: loops (boundary-edge graph)"
    );
    if q.non_manifold_vertices == 0 {
        assert_eq!(a.boundary_loops, q.boundary_loops, "{what}: loops");
    }
    let v = volumes(mesh);
    let scale: f64 = v.iter().map(|x| x.1.abs()).sum::<f64>().max(1e-300);
    let total: f64 = v.iter().map(|x| x.1).sum();
    assert!(
        (a.volume - total).abs() <= 1e-12 * scale,
        "{what}: volume {} against {total}",
        a.volume
    );
    let inward = v.iter().filter(|x| x.1 <= 0.0).count() as u64;
    assert_eq!(a.inward_components, inward, "{what}: inward");
    let smallest = v.iter().map(|x| x.1).reduce(f64::min);
    match (a.smallest_volume, smallest) {
        (Some(x), Some(y)) => assert!((x - y).abs() <= 1e-12 * scale, "{what}: {x} {y}"),
        (x, y) => assert_eq!(x, y, "{what}: smallest volume"),
    }
    a
}

/// A Moebius strip of `n` quads: one boundary loop, non-orientable.
fn moebius(n: u32) -> Mesh {
    let mut vertices = Vec::new();
    for i in 0..n {
        let u = std::f64::consts::TAU * i as f64 / n as f64;
        let radial = DVec3::new(u.cos(), u.sin(), 0.0);
        let d = radial * (u / 2.0).cos() + DVec3::Z * (u / 2.0).sin();
        vertices.extend([radial * 3.0 + d * 0.5, radial * 3.0 - d * 0.5]);
    }
    let (t, b) = (|i: u32| 2 * i, |i: u32| 2 * i + 1);
    let mut triangles = Vec::new();
    for i in 0..n - 1 {
        triangles.extend([[t(i), b(i), b(i + 1)], [t(i), b(i + 1), t(i + 1)]]);
    }
    // Half a turn: the top meets the bottom.
    let l = n - 1;
    triangles.extend([[t(l), b(l), t(0)], [t(l), t(0), b(0)]]);
    Mesh::new(vertices, triangles)
}

/// A cone of `n` sides with its apex at `apex` (index `apex_index` when
/// given, else a new vertex), opening along `axis`, capped when `closed`;
/// appended to `mesh`, wound outward.
fn add_cone(mesh: &mut Mesh, apex: DVec3, axis: f64, n: u32, closed: bool, shared: Option<u32>) {
    let a = shared.unwrap_or_else(|| {
        mesh.vertices.push(apex);
        mesh.vertices.len() as u32 - 1
    });
    let first = mesh.vertices.len() as u32;
    for i in 0..n {
        let u = std::f64::consts::TAU * i as f64 / n as f64;
        mesh.vertices
            .push(apex + DVec3::new(u.cos(), u.sin(), 2.0 * axis));
    }
    let centre = mesh.vertices.len() as u32;
    mesh.vertices.push(apex + DVec3::new(0.0, 0.0, 2.0 * axis));
    for i in 0..n {
        let (p, q) = (first + i, first + (i + 1) % n);
        let (side, cap) = match axis > 0.0 {
            true => ([a, q, p], [centre, p, q]),
            false => ([a, p, q], [centre, q, p]),
        };
        mesh.triangles.push(side);
        if closed {
            mesh.triangles.push(cap);
        }
    }
}

#[test]
fn a_sphere_is_one_closed_piece_of_its_volume() {
    let a = check(&icosphere(3), "sphere");
    assert_eq!((a.components, a.closed_components), (1, 1));
    assert_eq!((a.boundary_edges, a.euler_characteristic), (0, 2));
    // An icosphere of 1280 triangles holds a little less than 4/3 pi.
    assert!(a.volume > 4.0 && a.volume < 4.0 / 3.0 * std::f64::consts::PI);
}

#[test]
fn an_inside_out_sphere_has_a_negative_volume() {
    let mut m = icosphere(2);
    m.triangles.iter_mut().for_each(|t| t.swap(1, 2));
    let a = check(&m, "inside out");
    assert_eq!((a.closed_components, a.inward_components), (1, 1));
    assert!(a.volume < -4.0, "{}", a.volume);
    assert_eq!(a.smallest_volume, Some(a.volume));
    let broken = Promise::CLOSED.broken_by(&a);
    assert!(matches!(
        broken[..],
        [Failure::Inward { components: 1, .. }]
    ));
}

#[test]
fn a_torus_a_grid_and_two_spheres() {
    let a = check(&torus(2.0, 0.5, 24, 12), "torus");
    assert_eq!((a.closed_components, a.euler_characteristic), (1, 0));
    let a = check(&grid(6, 4, DVec2::new(3.0, 2.0)), "grid");
    assert_eq!(
        (a.boundary_loops, a.boundary_edges, a.closed_components),
        (1, 20, 0)
    );
    let mut two = icosphere(2);
    let far = icosphere(1);
    let n = two.vertices.len() as u32;
    two.vertices
        .extend(far.vertices.iter().map(|p| *p * 0.5 + DVec3::splat(4.0)));
    two.triangles
        .extend(far.triangles.iter().map(|t| t.map(|i| i + n)));
    let a = check(&two, "two spheres");
    assert_eq!((a.components, a.closed_components), (2, 2));
    assert!(Promise::CLOSED.broken_by(&a).is_empty());
}

#[test]
fn a_moebius_strip_has_one_loop_and_an_inconsistent_edge() {
    let a = check(&moebius(16), "moebius");
    assert_eq!((a.boundary_loops, a.components), (1, 1));
    assert!(a.inconsistent_edges >= 1);
    assert_eq!(a.euler_characteristic, 0);
}

#[test]
fn a_flipped_triangle_has_three_inconsistent_edges() {
    let mut m = icosphere(1);
    m.triangles[5].swap(0, 1);
    let a = check(&m, "flipped");
    assert_eq!((a.inconsistent_edges, a.boundary_edges), (3, 0));
    // Still closed (the definition is quality's): its volume is off.
    assert_eq!(a.closed_components, 1);
    let broken = Promise::CLOSED.broken_by(&a);
    assert_eq!(broken, [Failure::InconsistentEdges(3)]);
}

#[test]
fn a_fin_is_one_non_manifold_edge() {
    let mut m = icosphere(1);
    let [a0, b0, _] = m.triangles[0];
    m.vertices.push(DVec3::new(3.0, 0.0, 0.0));
    let fin = m.vertices.len() as u32 - 1;
    m.triangles.push([a0, b0, fin]);
    let a = check(&m, "fin");
    assert_eq!((a.non_manifold_edges, a.non_manifold_vertices), (1, 0));
    assert_eq!((a.boundary_edges, a.boundary_loops), (2, 1));
    assert_eq!(a.closed_components, 0);
    assert_eq!(
        Promise::DIRECTED_EDGES.broken_by(&a),
        [Failure::NonManifoldEdges(1)]
    );
}

#[test]
fn two_cones_touching_at_the_apex_make_a_non_manifold_vertex() {
    for closed in [true, false] {
        let mut m = Mesh::default();
        add_cone(&mut m, DVec3::ZERO, 1.0, 8, closed, None);
        add_cone(&mut m, DVec3::ZERO, -1.0, 8, closed, Some(0));
        let a = check(&m, &format!("cones, closed {closed}"));
        assert_eq!((a.non_manifold_vertices, a.non_manifold_edges), (1, 0));
        assert_eq!(a.components, 1);
        // Not closed whatever the caps: quality's definition.
        assert_eq!(a.closed_components, 0);
        assert_eq!(a.boundary_loops, if closed { 0 } else { 2 });
    }
}

/// Where two loops touch at a bow-tie vertex the boundary-edge graph is
/// one component; `quality` splits the vertex per fan and counts two.
#[test]
fn a_bow_tie_is_one_loop_here_and_two_for_quality() {
    let vertices = vec![
        DVec3::ZERO,
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(1.0, 1.0, 0.0),
        DVec3::new(-1.0, 0.0, 0.0),
        DVec3::new(-1.0, -1.0, 0.0),
    ];
    let m = Mesh::new(vertices, vec![[0, 1, 2], [0, 3, 4]]);
    let a = check(&m, "bow tie");
    assert_eq!((a.non_manifold_vertices, a.boundary_loops), (1, 1));
    assert_eq!(quality(&m).boundary_loops, 2);
}

#[test]
fn a_sphere_with_a_hole_breaks_the_closed_promise() {
    let mut m = icosphere(2);
    // Remove the star of vertex 0: one hole of five edges.
    m.triangles.retain(|t| !t.contains(&0));
    let a = check(&m, "holed sphere");
    assert_eq!((a.boundary_edges, a.boundary_loops), (5, 1));
    assert_eq!((a.closed_components, a.euler_characteristic), (0, 1));
    assert_eq!(
        Promise::CLOSED.broken_by(&a),
        [Failure::BoundaryEdges { edges: 5, loops: 1 }]
    );
    assert!(Promise::DIRECTED_EDGES.broken_by(&a).is_empty());
}

/// Triangles over few vertices, so edges are shared by many and indices
/// repeat: every kind of defect at once.
fn random_mesh(seed: u64, vertices: u64, triangles: usize) -> Mesh {
    let mut rng = Rng::new(seed);
    let vs = (0..vertices)
        .map(|_| DVec3::new(rng.uniform(), rng.uniform(), rng.uniform()) + DVec3::splat(1e3))
        .collect();
    let ts = (0..triangles)
        .map(|_| [0; 3].map(|_: u32| rng.below(vertices) as u32))
        .collect();
    Mesh::new(vs, ts)
}

#[test]
fn random_meshes_equal_quality() {
    for seed in 0..40u64 {
        let n = 4 + seed % 30;
        let m = random_mesh(seed, n, (3 * n + seed) as usize);
        check(&m, &format!("random mesh, seed {seed}"));
    }
    // Sparse ones: many pieces, some single triangles, some closed.
    for seed in 100..110u64 {
        let m = random_mesh(seed, 300, 60);
        check(&m, &format!("sparse random mesh, seed {seed}"));
    }
}

#[test]
fn tiny_buffers_merged_in_rounds_give_the_same_audit() {
    let mut shapes = vec![
        ("torus", torus(2.0, 0.5, 24, 12)),
        ("moebius", moebius(40)),
        ("sphere", icosphere(3)),
    ];
    for seed in [3u64, 17] {
        shapes.push(("random", random_mesh(seed, 50, 400)));
    }
    for (what, m) in shapes {
        // 3 records of every topological triangle, 6 a run: hundreds of
        // runs (the sphere's 3840 records make 640), merged 3 at a time.
        let (small, big) = (audit(&m, TINY), audit(&m, Sizes::DEFAULT));
        // A vertex's corners are sorted before they count, so even the
        // sums are the same bits.
        assert_eq!(small, big, "{what}");
    }
}

#[test]
fn the_writer_audits_and_keeps_a_broken_promise_apart() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("holed.ply");
    let mut m = icosphere(2);
    m.triangles.retain(|t| !t.contains(&0));
    // Promising nothing: written, the audit in hand.
    let written = crate::mesh::write_mesh(&path, &m, MeshFormat::PlyBinary).unwrap();
    assert_eq!(written.audit, audit(&m, Sizes::DEFAULT));
    std::fs::remove_file(&path).unwrap();
    // Promising a closed surface: written as incomplete, and an error.
    let mut w = MeshWriter::create(&path, MeshFormat::PlyBinary)
        .unwrap()
        .promising(Promise::CLOSED);
    w.add_vertices(&m.vertices).unwrap();
    w.add_triangles(&m.triangles).unwrap();
    let err = w.finish().unwrap_err();
    let text = err.to_string();
    let MeshError::PromiseBroken {
        written, failures, ..
    } = err
    else {
        panic!("{err:?}")
    };
    assert_eq!(written, dir.path().join("holed.incomplete.ply"));
    assert_eq!(failures, [Failure::BoundaryEdges { edges: 5, loops: 1 }]);
    assert!(text.contains("5 boundary edges in 1 loop"), "{text}");
    assert!(text.contains("holed.incomplete.ply"), "{text}");
    assert!(!path.exists());
    let (v, t) = crate::io::read_mesh_any(&written).unwrap();
    assert_eq!(Mesh::new(v, t), m);
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
}

#[test]
fn incomplete_names_keep_the_extension() {
    let p = |s: &str| incomplete_path(Path::new(s));
    assert_eq!(p("/a/dragon.ply"), Path::new("/a/dragon.incomplete.ply"));
    assert_eq!(p("out.obj"), Path::new("out.incomplete.obj"));
    assert_eq!(p("/a/mesh"), Path::new("/a/mesh.incomplete"));
}

#[test]
fn the_summary_names_what_it_counted() {
    let a = audit(&icosphere(1), Sizes::DEFAULT);
    let line = a.to_string();
    assert!(
        line.starts_with(
            "1 piece, closed, 0 non-manifold edges, 0 non-manifold vertices, 0 inconsistently wound, volume +"
        ),
        "{line}"
    );
    assert!(line.ends_with("Euler characteristic 2"), "{line}");
    let g = audit(&grid(2, 2, DVec2::ONE), Sizes::DEFAULT).to_string();
    assert!(
        g.starts_with("1 piece, 1 boundary loop (8 boundary edges), "),
        "{g}"
    );
}
