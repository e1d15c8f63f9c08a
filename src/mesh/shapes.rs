//! Procedural meshes with known geometry and topology, for tests, benches
//! and demos: a subdivided icosahedron (sphere, genus 0), a torus (genus 1),
//! a planar grid (a disc with one boundary loop), all consistently
//! oriented (outward normals for the closed ones), and a Moebius strip
//! (not orientable).

use super::Mesh;
use glam::DVec3;
use std::collections::HashMap;

/// Unit icosphere: the icosahedron with each triangle split in four
/// `subdivisions` times, vertices pushed onto the unit sphere.
/// Triangles: 20 * 4^subdivisions.
pub fn icosphere(subdivisions: u32) -> Mesh {
    let mut mesh = icosahedron();
    for _ in 0..subdivisions {
        mesh = subdivide(&mesh);
    }
    mesh
}

/// The unit icosahedron of the synthetic-scan generator, as a [`Mesh`].
fn icosahedron() -> Mesh {
    let ico = crate::synth::TriMesh::icosahedron(1.0);
    Mesh::new(ico.vertices, ico.faces)
}

/// One 1-to-4 split; edge midpoints are shared through a map that is only
/// looked up, never iterated, so the result is deterministic.
fn subdivide(mesh: &Mesh) -> Mesh {
    let mut vertices = mesh.vertices.clone();
    let mut midpoints: HashMap<(u32, u32), u32> = HashMap::new();
    let mut midpoint = |a: u32, b: u32, vertices: &mut Vec<DVec3>| -> u32 {
        let key = (a.min(b), a.max(b));
        *midpoints.entry(key).or_insert_with(|| {
            let m = (vertices[a as usize] + vertices[b as usize]).normalize();
            vertices.push(m);
            (vertices.len() - 1) as u32
        })
    };
    let mut triangles = Vec::with_capacity(mesh.triangles.len() * 4);
    for &[a, b, c] in &mesh.triangles {
        let ab = midpoint(a, b, &mut vertices);
        let bc = midpoint(b, c, &mut vertices);
        let ca = midpoint(c, a, &mut vertices);
        triangles.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
    }
    Mesh::new(vertices, triangles)
}

/// Moebius strip: `n` quads (two triangles each) round a circle of radius
/// 2, 0.6 wide, its two rails swapped where it closes (the half twist):
/// one boundary loop, Euler characteristic 0, not orientable; its odd
/// cycle of triangles is `2 n` long.
pub fn moebius(n: u32) -> Mesh {
    let mut vertices = Vec::with_capacity(2 * n as usize);
    for i in 0..n {
        let u = std::f64::consts::TAU * i as f64 / n as f64;
        let radial = DVec3::new(u.cos(), u.sin(), 0.0);
        let across = radial * (u / 2.0).cos() + DVec3::Z * (u / 2.0).sin();
        for s in [-0.3, 0.3] {
            vertices.push(radial * 2.0 + across * s);
        }
    }
    let mut triangles = Vec::with_capacity(2 * n as usize);
    for i in 0..n {
        let (a, b) = (2 * i, 2 * i + 1);
        let (c, d) = if i + 1 < n {
            (2 * i + 2, 2 * i + 3)
        } else {
            (1, 0)
        };
        triangles.extend([[a, c, b], [b, c, d]]);
    }
    Mesh::new(vertices, triangles)
}

/// Torus around the z axis: tube radius `minor` around a circle of radius
/// `major`, `n_major x n_minor` quads split into two triangles each.
/// Closed, genus 1 (Euler characteristic 0) for n_major, n_minor >= 3.
pub fn torus(major: f64, minor: f64, n_major: u32, n_minor: u32) -> Mesh {
    let mut vertices = Vec::with_capacity((n_major * n_minor) as usize);
    for i in 0..n_major {
        let u = std::f64::consts::TAU * i as f64 / n_major as f64;
        for j in 0..n_minor {
            let v = std::f64::consts::TAU * j as f64 / n_minor as f64;
            let r = major + minor * v.cos();
            vertices.push(DVec3::new(r * u.cos(), r * u.sin(), minor * v.sin()));
        }
    }
    let id = |i: u32, j: u32| (i % n_major) * n_minor + (j % n_minor);
    let mut triangles = Vec::with_capacity(2 * vertices.len());
    for i in 0..n_major {
        for j in 0..n_minor {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            triangles.extend([[a, b, c], [a, c, d]]);
        }
    }
    Mesh::new(vertices, triangles)
}

/// Planar grid in z = 0 over `[0, size.x] x [0, size.y]` with `nx x ny`
/// cells, two triangles per cell, normals +z. Vertex `(i, j)` has index
/// `j * (nx + 1) + i`.
pub fn grid(nx: u32, ny: u32, size: glam::DVec2) -> Mesh {
    let mut vertices = Vec::with_capacity(((nx + 1) * (ny + 1)) as usize);
    for j in 0..=ny {
        for i in 0..=nx {
            let x = size.x * i as f64 / nx.max(1) as f64;
            let y = size.y * j as f64 / ny.max(1) as f64;
            vertices.push(DVec3::new(x, y, 0.0));
        }
    }
    let id = |i: u32, j: u32| j * (nx + 1) + i;
    let mut triangles = Vec::with_capacity(2 * (nx * ny) as usize);
    for j in 0..ny {
        for i in 0..nx {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            triangles.extend([[a, b, c], [a, c, d]]);
        }
    }
    Mesh::new(vertices, triangles)
}
