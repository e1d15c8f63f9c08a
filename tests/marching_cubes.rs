//! Marching cubes on the global lattice: the generated case table checked
//! exhaustively, topology on random fields, analytic sphere and torus,
//! undefined corners, and tiled == untiled. The edge-use checker is local.

use std::collections::{BTreeMap, BTreeSet, HashMap};

use glam::DVec3;
use scanmesh::recon::implicit::lattice::{edge_from_key, edge_key, Lattice};
use scanmesh::recon::implicit::mc_table::{table, CORNER_OFFSETS, EDGE_AXIS, EDGE_CORNERS};
use scanmesh::recon::implicit::polygonize::{polygonize_cube, polygonize_field, IndexedMesh};
use scanmesh::synth::Rng;

// ---------- local edge-use checker ----------

/// Directed edge uses; error if a directed edge is used twice, a triangle
/// repeats a vertex, or an undirected edge is used more than twice.
fn half_edges(tris: &[[u32; 3]]) -> Result<BTreeMap<(u32, u32), usize>, String> {
    let mut uses = BTreeMap::new();
    for (t, &[a, b, c]) in tris.iter().enumerate() {
        if a == b || b == c || c == a {
            return Err(format!("triangle {t} repeats a vertex: {:?}", [a, b, c]));
        }
        for e in [(a, b), (b, c), (c, a)] {
            *uses.entry(e).or_insert(0) += 1;
            if uses[&e] > 1 {
                return Err(format!(
                    "directed edge {e:?} used twice (inconsistent orientation)"
                ));
            }
        }
    }
    Ok(uses)
}

/// Directed edges without a reverse twin (the open boundary).
fn boundary_edges(tris: &[[u32; 3]]) -> Result<Vec<(u32, u32)>, String> {
    let uses = half_edges(tris)?;
    Ok(uses
        .keys()
        .filter(|(a, b)| !uses.contains_key(&(*b, *a)))
        .copied()
        .collect())
}

/// The link of every vertex (opposite edges b->c of its triangles) must be
/// one cycle, or one path on the boundary.
fn check_vertex_manifold(mesh: &IndexedMesh) -> Result<(), String> {
    let mut link: Vec<Vec<(u32, u32)>> = vec![Vec::new(); mesh.vertices.len()];
    for &[a, b, c] in &mesh.triangles {
        link[a as usize].push((b, c));
        link[b as usize].push((c, a));
        link[c as usize].push((a, b));
    }
    for (v, edges) in link.iter().enumerate() {
        if edges.is_empty() {
            return Err(format!("vertex {v} is in no triangle"));
        }
        let next: BTreeMap<u32, u32> = edges.iter().copied().collect();
        let heads: BTreeSet<u32> = edges.iter().map(|e| e.1).collect();
        if next.len() != edges.len() || heads.len() != edges.len() {
            return Err(format!("vertex {v}: link branches"));
        }
        let start = edges
            .iter()
            .map(|e| e.0)
            .find(|x| !heads.contains(x))
            .unwrap_or(edges[0].0);
        let (mut x, mut walked) = (start, 0);
        while let Some(&y) = next.get(&x) {
            walked += 1;
            x = y;
            if x == start {
                break;
            }
        }
        if walked != edges.len() {
            return Err(format!(
                "vertex {v}: link has {} edges, one walk covers {walked}",
                edges.len()
            ));
        }
    }
    Ok(())
}

fn euler(mesh: &IndexedMesh) -> i64 {
    let edges: BTreeSet<(u32, u32)> = mesh
        .triangles
        .iter()
        .flat_map(|&[a, b, c]| [(a, b), (b, c), (c, a)])
        .map(|(a, b)| (a.min(b), a.max(b)))
        .collect();
    mesh.vertices.len() as i64 - edges.len() as i64 + mesh.triangles.len() as i64
}

fn components(n: usize, tris: &[[u32; 3]]) -> usize {
    let mut parent: Vec<usize> = (0..n).collect();
    fn root(p: &mut [usize], mut x: usize) -> usize {
        while p[x] != x {
            p[x] = p[p[x]];
            x = p[x];
        }
        x
    }
    for &[a, b, c] in tris {
        for (u, v) in [(a, b), (b, c)] {
            let (ru, rv) = (root(&mut parent, u as usize), root(&mut parent, v as usize));
            parent[ru] = rv;
        }
    }
    let used: BTreeSet<u32> = tris.iter().flatten().copied().collect();
    used.iter()
        .map(|&v| root(&mut parent, v as usize))
        .collect::<BTreeSet<_>>()
        .len()
}

/// Closed, consistently oriented, edge- and vertex-manifold.
fn check_closed_manifold(mesh: &IndexedMesh) -> Result<(), String> {
    let open = boundary_edges(&mesh.triangles)?;
    if !open.is_empty() {
        return Err(format!(
            "{} boundary edges, first {:?}",
            open.len(),
            open[0]
        ));
    }
    check_vertex_manifold(mesh)
}

fn tri_normal(mesh: &IndexedMesh, t: [u32; 3]) -> (DVec3, DVec3) {
    let [a, b, c] = t.map(|i| mesh.vertices[i as usize]);
    ((b - a).cross(c - a), (a + b + c) / 3.0)
}

fn signed_volume(mesh: &IndexedMesh) -> f64 {
    mesh.triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| mesh.vertices[i as usize]);
            a.dot(b.cross(c)) / 6.0
        })
        .sum()
}

// ---------- cube-local helpers for the table check ----------

fn positive(case: usize, c: usize) -> bool {
    case & (1 << c) != 0
}

fn is_cut(case: usize, e: usize) -> bool {
    let [lo, hi] = EDGE_CORNERS[e];
    positive(case, lo) != positive(case, hi)
}

/// Faces (axis, side) containing cube edge `e`.
fn faces_of_edge(e: usize) -> Vec<(usize, i64)> {
    let lo = CORNER_OFFSETS[EDGE_CORNERS[e][0]];
    (0..3)
        .filter(|&a| a != EDGE_AXIS[e] as usize)
        .map(|a| (a, lo[a]))
        .collect()
}

fn shared_face(a: usize, b: usize) -> Option<(usize, i64)> {
    let fb = faces_of_edge(b);
    faces_of_edge(a).into_iter().find(|f| fb.contains(f))
}

fn midpoint(e: usize) -> DVec3 {
    let [lo, hi] = EDGE_CORNERS[e].map(|c| DVec3::from_array(CORNER_OFFSETS[c].map(|x| x as f64)));
    (lo + hi) * 0.5
}

/// One case of the table against the face rule, independently re-derived.
fn check_case(case: usize) -> Result<(), String> {
    let tris: Vec<[u32; 3]> = table()
        .map_err(|e| e.to_string())?
        .case(case as u8)
        .triangles()
        .iter()
        .map(|t| t.map(u32::from))
        .collect();
    let used: BTreeSet<usize> = tris.iter().flatten().map(|&e| e as usize).collect();
    let cut: BTreeSet<usize> = (0..12).filter(|&e| is_cut(case, e)).collect();
    if used != cut {
        return Err(format!("edges used {used:?} != sign-change edges {cut:?}"));
    }
    let uses = half_edges(&tris)?;
    let mut on_face: BTreeMap<(usize, i64), Vec<(usize, usize)>> = BTreeMap::new();
    for &(a, b) in uses.keys() {
        let (a, b) = (a as usize, b as usize);
        let twin = uses.contains_key(&(b as u32, a as u32));
        match (twin, shared_face(a, b)) {
            (true, Some(f)) => return Err(format!("diagonal {a}-{b} lies in face {f:?}")),
            (false, None) => return Err(format!("boundary segment {a}->{b} is not on a face")),
            (false, Some(f)) => on_face.entry(f).or_default().push((a, b)),
            (true, None) => {}
        }
    }
    for axis in 0..3 {
        for side in 0..2 {
            check_face(
                case,
                (axis, side),
                on_face.remove(&(axis, side)).unwrap_or_default(),
            )?;
        }
    }
    let mesh = IndexedMesh {
        vertices: vec![DVec3::ZERO; 12],
        keys: vec![0; 12],
        triangles: tris.clone(),
    };
    let loops = components(12, &tris);
    let chi = euler(&mesh) - (12 - cut.len()) as i64;
    if chi != loops as i64 {
        return Err(format!(
            "patch is not a union of disks: chi {chi}, components {loops}"
        ));
    }
    Ok(())
}

/// The segments on one face pair its cut edges, cut off positive corners on
/// ambiguous faces, and have the positive corners on their left from outside.
fn check_face(
    case: usize,
    (axis, side): (usize, i64),
    segs: Vec<(usize, usize)>,
) -> Result<(), String> {
    let cuts: BTreeSet<usize> = (0..12)
        .filter(|&e| is_cut(case, e) && faces_of_edge(e).contains(&(axis, side)))
        .collect();
    let ends: Vec<usize> = segs.iter().flat_map(|&(a, b)| [a, b]).collect();
    if ends.len() != cuts.len() || ends.iter().copied().collect::<BTreeSet<_>>() != cuts {
        return Err(format!(
            "face {axis}/{side}: segments {segs:?} do not pair cuts {cuts:?}"
        ));
    }
    let corners: Vec<usize> = (0..8)
        .filter(|&c| CORNER_OFFSETS[c][axis] == side)
        .collect();
    let mut n = DVec3::ZERO;
    n[axis] = if side == 1 { 1.0 } else { -1.0 };
    for &(a, b) in &segs {
        let common = EDGE_CORNERS[a]
            .iter()
            .find(|c| EDGE_CORNERS[b].contains(c))
            .copied();
        if cuts.len() == 4 && !common.is_some_and(|c| positive(case, c)) {
            return Err(format!(
                "ambiguous face {axis}/{side}: segment {a}-{b} does not cut off a positive corner"
            ));
        }
        let (ma, mb) = (midpoint(a), midpoint(b));
        let left = n.cross(mb - ma);
        for &c in &corners {
            let p = DVec3::from_array(CORNER_OFFSETS[c].map(|x| x as f64));
            let near = cuts.len() == 2 || common == Some(c);
            if near && positive(case, c) && left.dot(p - ma) <= 0.0 {
                return Err(format!(
                    "face {axis}/{side}: positive corner {c} right of {a}->{b}"
                ));
            }
        }
    }
    Ok(())
}

#[test]
fn a_every_case_uses_exactly_the_sign_change_edges_with_face_consistent_segments() {
    for case in 0..256 {
        if let Err(e) = check_case(case) {
            panic!("case {case:#04x} ({case:08b}): {e}");
        }
    }
}

// ---------- fields on a lattice ----------

/// Cubes `[lo, hi)` on every axis.
fn box_cells(lo: [i64; 3], hi: [i64; 3]) -> Vec<[i64; 3]> {
    let mut out = Vec::new();
    for x in lo[0]..hi[0] {
        for y in lo[1]..hi[1] {
            for z in lo[2]..hi[2] {
                out.push([x, y, z]);
            }
        }
    }
    out
}

/// Lattice edges (lower corner, axis) with a sign change among `cells`.
fn sign_change_edges(
    lat: &Lattice,
    cells: &[[i64; 3]],
    f: &dyn Fn(DVec3) -> Option<f64>,
) -> BTreeSet<u64> {
    let mut out = BTreeSet::new();
    for &cell in cells {
        let vals: Vec<Option<f64>> = CORNER_OFFSETS
            .iter()
            .map(|o| f(lat.corner([cell[0] + o[0], cell[1] + o[1], cell[2] + o[2]])))
            .collect();
        if vals.iter().any(Option::is_none) {
            continue;
        }
        for e in 0..12 {
            let [lo, hi] = EDGE_CORNERS[e];
            if (vals[lo] > Some(0.0)) != (vals[hi] > Some(0.0)) {
                let o = CORNER_OFFSETS[lo];
                out.insert(
                    edge_key(
                        [cell[0] + o[0], cell[1] + o[1], cell[2] + o[2]],
                        EDGE_AXIS[e],
                    )
                    .unwrap(),
                );
            }
        }
    }
    out
}

/// Every vertex lies on its keyed lattice edge.
fn check_vertices_on_edges(lat: &Lattice, mesh: &IndexedMesh) -> Result<(), String> {
    for (v, (&p, &key)) in mesh.vertices.iter().zip(&mesh.keys).enumerate() {
        let (c, axis) = edge_from_key(key).map_err(|e| e.to_string())?;
        let (a, p0) = (axis as usize, lat.corner(c));
        let along = (p[a] - p0[a]) / lat.cell;
        let mut off = p - p0;
        off[a] = 0.0;
        if !(-1e-9..=1.0 + 1e-9).contains(&along) || off != DVec3::ZERO {
            return Err(format!("vertex {v} at {p:?} is off its edge {c:?}/{axis}"));
        }
    }
    Ok(())
}

#[test]
fn b_random_fields_give_closed_oriented_manifolds() {
    for seed in 0..400u64 {
        let mut rng = Rng::new(seed);
        let n = 2 + (rng.next_u64() % 7) as i64;
        let p_pos = 0.2 + 0.6 * rng.uniform();
        let lat = Lattice::new(
            DVec3::new(rng.uniform(), -rng.uniform(), 3.0 * rng.uniform()),
            0.1 + rng.uniform(),
        )
        .unwrap();
        let mut values = HashMap::new();
        for c in box_cells([0; 3], [n + 1; 3]) {
            let boundary = c.iter().any(|&x| x == 0 || x == n);
            let r = rng.uniform();
            let mag = if r < 0.1 { 0.0 } else { rng.uniform() };
            let v = if !boundary && rng.uniform() < p_pos {
                mag + 1e-3
            } else {
                -mag
            };
            values.insert(lat.cell_of(lat.corner(c) + DVec3::splat(0.5 * lat.cell)), v);
        }
        let f = |p: DVec3| {
            values
                .get(&lat.cell_of(p + DVec3::splat(0.5 * lat.cell)))
                .copied()
        };
        let cells = box_cells([0; 3], [n; 3]);
        let mesh = polygonize_field(&lat, cells.iter().copied(), f).unwrap();
        let fail = |what: String| -> () { panic!("seed {seed} (n = {n}): {what}") };
        check_closed_manifold(&mesh).unwrap_or_else(fail);
        check_vertices_on_edges(&lat, &mesh).unwrap_or_else(fail);
        let expected: BTreeSet<u64> = sign_change_edges(&lat, &cells, &f);
        if mesh.keys.iter().copied().collect::<BTreeSet<_>>() != expected
            || mesh.keys.len() != expected.len()
        {
            fail(format!(
                "{} vertices, {} sign-change edges",
                mesh.keys.len(),
                expected.len()
            ));
        }
        let reversed = polygonize_field(&lat, cells.iter().rev().copied(), f).unwrap();
        if key_triangles(&reversed) != key_triangles(&mesh) {
            fail("cube order changed the triangle set".into());
        }
    }
}

// ---------- analytic surfaces ----------

struct Surface {
    lat: Lattice,
    cells: Vec<[i64; 3]>,
    mesh: IndexedMesh,
}

/// Narrow band: cubes whose centre is within one cell of the zero set of the
/// distance field `f` (every cube the surface crosses has |f(centre)| <=
/// half a diagonal < one cell).
fn band_surface(
    lat: Lattice,
    lo: [i64; 3],
    hi: [i64; 3],
    f: &dyn Fn(DVec3) -> Option<f64>,
) -> Surface {
    let half = DVec3::splat(0.5 * lat.cell);
    let cells: Vec<[i64; 3]> = box_cells(lo, hi)
        .into_iter()
        .filter(|&c| f(lat.corner(c) + half).is_some_and(|v| v.abs() < lat.cell))
        .collect();
    let mesh = polygonize_field(&lat, cells.iter().copied(), f).unwrap();
    Surface { lat, cells, mesh }
}

const SPHERE_C: DVec3 = DVec3::new(0.31, -0.17, 0.23);
const SPHERE_R: f64 = 1.0;

fn sphere(p: DVec3) -> Option<f64> {
    Some((p - SPHERE_C).length() - SPHERE_R)
}

fn sphere_surface() -> Surface {
    let lat = Lattice::new(DVec3::new(-2.05, -1.97, -2.11), 0.13).unwrap();
    band_surface(lat, [0; 3], [34; 3], &sphere)
}

#[test]
fn c_sphere_is_a_closed_outward_genus_0_surface_near_the_sphere() {
    let s = sphere_surface();
    let (mesh, h) = (&s.mesh, s.lat.cell);
    check_closed_manifold(mesh).unwrap();
    check_vertices_on_edges(&s.lat, mesh).unwrap();
    assert_eq!(euler(mesh), 2);
    assert_eq!(components(mesh.vertices.len(), &mesh.triangles), 1);
    assert_eq!(
        mesh.keys.iter().copied().collect::<BTreeSet<_>>(),
        sign_change_edges(&s.lat, &s.cells, &sphere)
    );
    let worst = mesh
        .vertices
        .iter()
        .map(|&v| sphere(v).unwrap_or(f64::NAN).abs())
        .fold(0.0, f64::max);
    assert!(
        worst < 0.05 * h,
        "vertex off the sphere by {worst} (cell {h})"
    );
    for &t in &mesh.triangles {
        let (n, centroid) = tri_normal(mesh, t);
        if n.length() > 1e-6 * h * h {
            assert!(
                n.normalize().dot((centroid - SPHERE_C).normalize()) > 0.5,
                "inward or tilted triangle {t:?}"
            );
        }
    }
    let vol = signed_volume(mesh);
    let exact = 4.0 / 3.0 * std::f64::consts::PI * SPHERE_R.powi(3);
    // Chords cut inside a convex surface: a deficit of order (h / r)^2.
    assert!(
        (vol - exact).abs() < 0.03 * exact,
        "volume {vol} vs {exact}"
    );
}

const TORUS_R: f64 = 1.0;
const TORUS_A: f64 = 0.4;

fn torus(p: DVec3) -> Option<f64> {
    let ring = (p.x * p.x + p.y * p.y).sqrt() - TORUS_R;
    Some((ring * ring + p.z * p.z).sqrt() - TORUS_A)
}

fn torus_surface() -> Surface {
    let lat = Lattice::new(DVec3::new(-1.63, -1.58, -0.61), 0.1).unwrap();
    band_surface(lat, [0; 3], [33, 33, 13], &torus)
}

#[test]
fn d_torus_has_euler_characteristic_0() {
    let s = torus_surface();
    let mesh = &s.mesh;
    check_closed_manifold(mesh).unwrap();
    assert_eq!(euler(mesh), 0);
    assert_eq!(components(mesh.vertices.len(), &mesh.triangles), 1);
    for &t in &mesh.triangles {
        let (n, centroid) = tri_normal(mesh, t);
        let core = DVec3::new(centroid.x, centroid.y, 0.0).normalize() * TORUS_R;
        if n.length() > 1e-6 * s.lat.cell * s.lat.cell {
            assert!(n.dot(centroid - core) > 0.0, "inward triangle {t:?}");
        }
    }
}

// ---------- undefined corners ----------

#[test]
fn e_undefined_corners_open_the_surface_exactly_where_they_start() {
    let (z_lo, z_hi) = (SPHERE_C.z - 0.45, SPHERE_C.z + 0.5);
    let slab = |p: DVec3| {
        if (z_lo..=z_hi).contains(&p.z) {
            sphere(p)
        } else {
            None
        }
    };
    let s = sphere_surface();
    let mesh = polygonize_field(&s.lat, s.cells.iter().copied(), slab).unwrap();
    let open = boundary_edges(&mesh.triangles).unwrap();
    check_vertex_manifold(&mesh).unwrap();
    assert!(!open.is_empty());
    assert_eq!(euler(&mesh), 0, "a belt around the sphere is an annulus");
    let loops = components(
        mesh.vertices.len(),
        &open.iter().map(|&(a, b)| [a, b, b]).collect::<Vec<_>>(),
    );
    assert_eq!(loops, 2, "one rim at each slab face");
    let defined = |c: [i64; 3]| {
        CORNER_OFFSETS
            .iter()
            .all(|o| slab(s.lat.corner([c[0] + o[0], c[1] + o[1], c[2] + o[2]])).is_some())
    };
    for &(a, b) in &open {
        let [(ca, xa), (cb, xb)] = [a, b].map(|v| edge_from_key(mesh.keys[v as usize]).unwrap());
        let face = face_between(ca, xa as usize, cb, xb as usize)
            .unwrap_or_else(|| panic!("boundary edge {a}-{b} not on a lattice face"));
        let (min, axis) = face;
        let mut other = min;
        other[axis] -= 1;
        assert_ne!(
            defined(min),
            defined(other),
            "boundary edge {a}-{b}: both cubes at face {face:?} agree"
        );
    }
}

/// The lattice face (min corner, normal axis) holding both lattice edges:
/// their end points must span exactly a unit square.
fn face_between(ca: [i64; 3], xa: usize, cb: [i64; 3], xb: usize) -> Option<([i64; 3], usize)> {
    let (mut ea, mut eb) = (ca, cb);
    ea[xa] += 1;
    eb[xb] += 1;
    let pts = [ca, ea, cb, eb];
    let min: [i64; 3] = std::array::from_fn(|i| pts.iter().map(|p| p[i]).min().unwrap_or(0));
    let span: [i64; 3] =
        std::array::from_fn(|i| pts.iter().map(|p| p[i]).max().unwrap_or(0) - min[i]);
    let flat: Vec<usize> = (0..3).filter(|&i| span[i] == 0).collect();
    let unit = (0..3).filter(|&i| span[i] == 1).count() == 2;
    (flat.len() == 1 && unit).then(|| (min, flat[0]))
}

// ---------- tiled == untiled ----------

/// Triangles as key triples, rotated to start at the smallest key (keeps the
/// orientation).
fn key_triangles(mesh: &IndexedMesh) -> BTreeMap<[u64; 3], usize> {
    let mut out = BTreeMap::new();
    for t in &mesh.triangles {
        let k = t.map(|i| mesh.keys[i as usize]);
        let r = (0..3).min_by_key(|&i| k[i]).unwrap_or(0);
        *out.entry([k[r], k[(r + 1) % 3], k[(r + 2) % 3]])
            .or_insert(0) += 1;
    }
    out
}

#[test]
fn f_tiled_polygonization_equals_single_pass_bit_for_bit() {
    let s = torus_surface();
    let block = |c: [i64; 3]| {
        [
            (c[0] + 2).div_euclid(7),
            (c[1] - 1).div_euclid(5),
            c[2].div_euclid(6),
        ]
    };
    let mut blocks: BTreeMap<[i64; 3], Vec<[i64; 3]>> = BTreeMap::new();
    for &c in &s.cells {
        blocks.entry(block(c)).or_default().push(c);
    }
    assert!(blocks.len() > 10);
    let mut tris = BTreeMap::new();
    let mut pos: BTreeMap<u64, Bits3> = BTreeMap::new();
    let mut seen_in = BTreeMap::<u64, usize>::new();
    for cells in blocks.values() {
        let m = polygonize_field(&s.lat, cells.iter().copied(), torus).unwrap();
        for (t, n) in key_triangles(&m) {
            *tris.entry(t).or_insert(0) += n;
        }
        for (&k, &p) in m.keys.iter().zip(&m.vertices) {
            let bits = p.to_array().map(f64::to_bits);
            assert_eq!(
                *pos.entry(k).or_insert(bits),
                bits,
                "seam vertex {k:#x} differs between blocks"
            );
            *seen_in.entry(k).or_insert(0) += 1;
        }
    }
    assert!(
        seen_in.values().filter(|&&n| n > 1).count() > 100,
        "too few seam vertices to test"
    );
    assert_eq!(tris, key_triangles(&s.mesh));
    let single: BTreeMap<u64, Bits3> = s
        .mesh
        .keys
        .iter()
        .zip(&s.mesh.vertices)
        .map(|(&k, p)| (k, p.to_array().map(f64::to_bits)))
        .collect();
    assert_eq!(pos, single);
}

type Bits3 = [u64; 3];

// ---------- throughput (run with --ignored --nocapture in release) ----------

#[test]
#[ignore]
fn throughput_of_polygonize_cube() {
    let lat = Lattice::new(DVec3::new(-1.3, -1.3, -1.3), 0.02).unwrap();
    let n = 130i64;
    let idx = |c: [i64; 3]| ((c[0] * (n + 1) + c[1]) * (n + 1) + c[2]) as usize;
    let vals: Vec<f64> = box_cells([0; 3], [n + 1; 3])
        .into_iter()
        .map(|c| sphere(lat.corner(c)).unwrap_or(0.0))
        .collect();
    let corner_vals =
        |c: [i64; 3]| CORNER_OFFSETS.map(|o| vals[idx([c[0] + o[0], c[1] + o[1], c[2] + o[2]])]);
    let cells = box_cells([0; 3], [n; 3]);
    let cut: Vec<([i64; 3], [f64; 8])> = cells
        .iter()
        .map(|&c| (c, corner_vals(c)))
        .filter(|(_, v)| v.iter().any(|&x| x > 0.0) && v.iter().any(|&x| x <= 0.0))
        .collect();
    let mut out = Vec::with_capacity(1 << 20);
    let start = std::time::Instant::now();
    for &c in &cells {
        polygonize_cube(&lat, c, &corner_vals(c), &mut out).unwrap();
    }
    let dense = start.elapsed().as_secs_f64();
    let reference = polygonize_field(&lat, cells.iter().copied(), sphere).unwrap();
    assert_eq!(out.len(), reference.triangles.len());
    let reps = 20;
    let start = std::time::Instant::now();
    for _ in 0..reps {
        out.clear();
        for (c, v) in &cut {
            polygonize_cube(&lat, *c, v, &mut out).unwrap();
        }
    }
    let crossing = start.elapsed().as_secs_f64();
    assert_eq!(out.len(), reference.triangles.len());
    println!(
        "dense: {} cubes in {dense:.3} s = {:.1} M cubes/s; surface cubes only: {:.1} M cubes/s ({} cubes, {} triangles)",
        cells.len(),
        cells.len() as f64 / dense / 1e6,
        (reps * cut.len()) as f64 / crossing / 1e6,
        cut.len(),
        out.len()
    );
}
