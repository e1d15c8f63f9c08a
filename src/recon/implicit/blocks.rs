//! Flat blocks of the lattice re-triangulated with fewer triangles
//! (issue 43): the marching cubes' triangles inside a block of [`BLOCK`]^3
//! cubes that form one flat disk are replaced by a triangulation of the
//! disk's boundary loop alone, where that loses no more than a tolerance.
//!
//! Deviation from paper 1 section 2.6, which keeps every marching-cubes
//! triangle: on flat ground, walls and roofs a uniform lattice makes as
//! many triangles as on the dragon's scales (the cell is set by where the
//! surface bends most). A disk with `n` loop vertices and `m` inside has
//! `n + 2m - 2` triangles; its loop alone needs `n - 2`.
//!
//! Why blocks with fixed boundaries rather than an octree of cells: the
//! loop's vertices lie on the block's faces and are kept, so a block's
//! neighbours, re-triangulated or not, meet it along the same edges (no
//! crack, no transition cells), and a tile owns whole blocks
//! (`cubes::owns`), so what a block becomes depends on its own
//! triangles only: tiled == untiled and 1 == 2 threads hold as before.
//! The evaluations of the field are not fewer; only the mesh is smaller.
//!
//! What keeps the new triangles honest:
//! - every original and new triangle faces within [`MAX_TILT_DEGREES`] of
//!   the disk's mean normal, and the loop projected on that plane is a
//!   simple polygon, so its triangulation (ear clipping, the ear of
//!   largest smallest angle first) cannot fold;
//! - every vertex left out lies within the tolerance of the new triangles,
//!   and their mean offset (along the disk's normal) within
//!   [`BIAS_SHARE`] of it: noise about the new triangles averages out, a
//!   bend under them (the chord's sag on a curved part) does not;
//! - where the ears fail those tests, a fan round the inside vertex
//!   nearest the rim's centroid is tried (it halves the chords, so a
//!   quarter of the sag), if the rim is star-shaped from it in projection;
//! - no new edge joins two vertices of one block face, so a new triangle
//!   touches a neighbour block's triangles only at the loop's own
//!   vertices and edges (the triangles stay inside the block's box).

use super::lattice::edge_from_key;
use super::polygonize::CubeVertex;
use crate::mesh::closest::closest_point_on_triangle;
use crate::mesh::intersect::segments_meet2;
use crate::mesh::union_find::DisjointSets;
use crate::pipeline::KernelError;
use glam::{DVec2, DVec3};
use rayon::prelude::*;
use robust::{orient2d, Coord};

/// Cubes along each side of a block. 4: a flat disk across a block loses
/// about half its triangles (32 -> 14 for a level plane), and the block's
/// 8.8 spacings at the default cell stay well inside the flat parts of
/// ground and walls.
pub const BLOCK: i64 = 4;

/// Largest angle between any triangle of a merged disk (before and after)
/// and the disk's mean normal.
pub const MAX_TILT_DEGREES: f64 = 20.0;

/// Largest mean offset of the left-out vertices from the new triangles,
/// as a share of the tolerance: noise about the new triangles averages
/// out, a bend under them does not.
pub const BIAS_SHARE: f64 = 0.25;

/// One triangle of the tile's marching cubes.
pub type Triangle = [CubeVertex; 3];

/// The block holding `cube`.
pub fn block_of(cube: [i64; 3]) -> [i64; 3] {
    cube.map(|c| c.div_euclid(BLOCK))
}

/// The cube a marching-cubes triangle came from: along each axis the least
/// lower corner of its vertices' edges (a vertex on an edge along that
/// axis gives the cube's own index; the others give it or one more, and
/// not all three lie on the far face).
fn cube_of(t: &Triangle) -> Result<[i64; 3], KernelError> {
    let mut cube = [i64::MAX; 3];
    for v in t {
        let (c, _) = edge_from_key(v.key).map_err(KernelError::failed)?;
        for a in 0..3 {
            cube[a] = cube[a].min(c[a]);
        }
    }
    Ok(cube)
}

/// Replaces the triangles of every flat disk block by its loop's
/// triangulation where no left-out vertex lies farther than `tolerance`
/// from the new triangles. The result lists blocks in key order, each
/// block's triangles in their order (kept) or the loop's (merged).
pub fn merge_flat_blocks(
    triangles: Vec<Triangle>,
    tolerance: f64,
) -> Result<Vec<Triangle>, KernelError> {
    let mut keyed: Vec<([i64; 3], Triangle)> = triangles
        .into_iter()
        .map(|t| Ok((block_of(cube_of(&t)?), t)))
        .collect::<Result<_, KernelError>>()?;
    // Stable: a block's triangles keep their order.
    keyed.par_sort_by_key(|e| e.0);
    let blocks: Vec<&[([i64; 3], Triangle)]> = keyed.chunk_by(|a, b| a.0 == b.0).collect();
    let merged: Vec<Vec<Triangle>> = blocks
        .par_iter()
        .map(|block| {
            let key = block[0].0;
            let tris: Vec<Triangle> = block.iter().map(|e| e.1).collect();
            match Disk::new(key, &tris).and_then(|d| d.merged(tolerance)) {
                Some(fewer) => fewer,
                None => tris,
            }
        })
        .collect();
    Ok(merged.into_iter().flatten().collect())
}

/// A block's triangles as one disk: local vertices (sorted by key), the
/// boundary loop in the triangles' winding, and each vertex's faces.
struct Disk {
    vertices: Vec<CubeVertex>,
    /// Per vertex, a bit per block face it lies on (0: inside the block).
    faces: Vec<u8>,
    triangles: Vec<[usize; 3]>,
    loop_: Vec<usize>,
    normal: DVec3,
}

impl Disk {
    /// `None` unless the triangles form one disk whose loop runs on the
    /// block's faces, with at least one vertex inside, all facing alike.
    fn new(block: [i64; 3], tris: &[Triangle]) -> Option<Disk> {
        let mut vertices: Vec<CubeVertex> = tris.iter().flatten().copied().collect();
        vertices.sort_by_key(|v| v.key);
        vertices.dedup_by_key(|v| v.key);
        let faces: Vec<u8> = vertices
            .iter()
            .map(|v| faces_of(block, v.key))
            .collect::<Option<_>>()?;
        if faces.iter().all(|&f| f != 0) {
            return None;
        }
        let local = |v: &CubeVertex| vertices.binary_search_by_key(&v.key, |w| w.key).ok();
        let triangles: Vec<[usize; 3]> = tris
            .iter()
            .map(|t| Some([local(&t[0])?, local(&t[1])?, local(&t[2])?]))
            .collect::<Option<_>>()?;
        let loop_ = boundary_loop(vertices.len(), &triangles)?;
        // The loop holds exactly the vertices on the block's faces.
        let on_loop = loop_.iter().filter(|&&v| faces[v] != 0).count();
        let on_faces = faces.iter().filter(|&&f| f != 0).count();
        if on_loop != loop_.len() || on_loop != on_faces {
            return None;
        }
        let normal = mean_normal(&vertices, &triangles)?;
        let disk = Disk {
            vertices,
            faces,
            triangles,
            loop_,
            normal,
        };
        disk.all_face(&disk.triangles).then_some(disk)
    }

    fn pos(&self, i: usize) -> DVec3 {
        self.vertices[i].pos
    }

    /// Whether every non-degenerate triangle faces within the tilt.
    fn all_face(&self, triangles: &[[usize; 3]]) -> bool {
        let cos = MAX_TILT_DEGREES.to_radians().cos();
        triangles.iter().all(|t| {
            let n = (self.pos(t[1]) - self.pos(t[0])).cross(self.pos(t[2]) - self.pos(t[0]));
            let len = n.length();
            len == 0.0 || n.dot(self.normal) >= cos * len
        })
    }

    /// The loop's triangulation, if it keeps every promise above.
    fn merged(&self, tolerance: f64) -> Option<Vec<Triangle>> {
        let flat = self.projected();
        if !simple_ccw(&flat) {
            return None;
        }
        let ears = clip_ears(
            &flat,
            &self.loop_,
            |a, b| self.faces[a] & self.faces[b] != 0,
            |t| min_angle(t.map(|i| self.pos(i))),
        );
        // The ears make fewest triangles; a fan around an inside vertex
        // halves the chords where the ears bend too far from it.
        let chosen = match ears {
            Some(e) if self.honest(&e, tolerance) => Some(e),
            _ => self.fan(&flat).filter(|f| self.honest(f, tolerance)),
        };
        chosen.map(|t| t.iter().map(|t| t.map(|i| self.vertices[i])).collect())
    }

    /// Whether `triangles` face like the disk and pass within `tolerance`
    /// of every vertex they leave out, without a bend under them.
    fn honest(&self, triangles: &[[usize; 3]], tolerance: f64) -> bool {
        if !self.all_face(triangles) {
            return false;
        }
        let kept = |v: usize| triangles.iter().any(|t| t.contains(&v));
        let out: Vec<usize> = (0..self.vertices.len()).filter(|&v| !kept(v)).collect();
        let offsets: Vec<f64> = out.iter().map(|&v| self.offset(v, triangles)).collect();
        let bias = offsets.iter().sum::<f64>() / offsets.len().max(1) as f64;
        offsets.iter().all(|d| d.abs() <= tolerance) && bias.abs() <= BIAS_SHARE * tolerance
    }

    /// The loop fanned around the inside vertex nearest the loop's
    /// centroid, if the loop is star-shaped from it in projection.
    fn fan(&self, flat: &[DVec2]) -> Option<Vec<[usize; 3]>> {
        let n = self.loop_.len();
        let centroid = self.loop_.iter().map(|&i| self.pos(i)).sum::<DVec3>() / n as f64;
        let centre = (0..self.vertices.len())
            .filter(|&v| self.faces[v] == 0)
            .min_by(|&a, &b| {
                let (da, db) = (
                    self.pos(a).distance_squared(centroid),
                    self.pos(b).distance_squared(centroid),
                );
                da.total_cmp(&db).then(a.cmp(&b))
            })?;
        let d = self.pos(centre) - self.pos(self.loop_[0]);
        let u = self.normal.any_orthonormal_vector();
        let c2 = DVec2::new(d.dot(u), d.dot(self.normal.cross(u)));
        (0..n)
            .map(|k| {
                let (a, b) = (k, (k + 1) % n);
                (orient2d(coord(c2), coord(flat[a]), coord(flat[b])) > 0.0).then_some([
                    centre,
                    self.loop_[a],
                    self.loop_[b],
                ])
            })
            .collect()
    }

    /// Vertex `v`'s offset from the nearest of `triangles`, along the
    /// disk's normal (positive on the side it faces).
    fn offset(&self, v: usize, triangles: &[[usize; 3]]) -> f64 {
        let p = self.pos(v);
        triangles
            .iter()
            .map(|t| closest_point_on_triangle(p, self.pos(t[0]), self.pos(t[1]), self.pos(t[2])))
            .map(|c| (p.distance_squared(c), (p - c).dot(self.normal)))
            .fold(
                (f64::INFINITY, 0.0),
                |best, d| if d.0 < best.0 { d } else { best },
            )
            .1
    }

    /// The loop's vertices on the plane of the mean normal.
    fn projected(&self) -> Vec<DVec2> {
        let n = self.normal;
        let u = n.any_orthonormal_vector();
        let v = n.cross(u);
        let o = self.pos(self.loop_[0]);
        self.loop_
            .iter()
            .map(|&i| {
                let d = self.pos(i) - o;
                DVec2::new(d.dot(u), d.dot(v))
            })
            .collect()
    }
}

/// Bits of the block faces lattice edge `key` lies on (bit `2a` the low
/// face across axis `a`, `2a + 1` the high one); `None` if the edge is not
/// the block's.
fn faces_of(block: [i64; 3], key: u64) -> Option<u8> {
    let (c, axis) = edge_from_key(key).ok()?;
    let mut bits = 0u8;
    for a in 0..3 {
        let lo = block[a] * BLOCK;
        let ok = if a == usize::from(axis) {
            (lo..lo + BLOCK).contains(&c[a])
        } else {
            (lo..=lo + BLOCK).contains(&c[a])
        };
        if !ok {
            return None;
        }
        if a != usize::from(axis) {
            if c[a] == lo {
                bits |= 1 << (2 * a);
            } else if c[a] == lo + BLOCK {
                bits |= 1 << (2 * a + 1);
            }
        }
    }
    Some(bits)
}

/// The one boundary loop of a connected disk (V - E + F = 1), in the
/// triangles' winding; `None` for anything else (an edge of three
/// triangles, an edge run twice one way, two loops, a closed piece).
fn boundary_loop(vertices: usize, triangles: &[[usize; 3]]) -> Option<Vec<usize>> {
    let mut directed: Vec<(usize, usize)> = triangles
        .iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .collect();
    directed.sort_unstable();
    if directed.windows(2).any(|w| w[0] == w[1]) {
        return None;
    }
    let has = |e: (usize, usize)| directed.binary_search(&e).is_ok();
    let boundary: Vec<(usize, usize)> = directed
        .iter()
        .copied()
        .filter(|&(a, b)| !has((b, a)))
        .collect();
    let undirected = (directed.len() + boundary.len()) / 2;
    if vertices as i64 - undirected as i64 + triangles.len() as i64 != 1 {
        return None;
    }
    let mut next = vec![usize::MAX; vertices];
    for &(a, b) in &boundary {
        if next[a] != usize::MAX {
            return None;
        }
        next[a] = b;
    }
    let start = boundary.first()?.0;
    let mut cycle = vec![start];
    let mut at = next[start];
    while at != start {
        if at == usize::MAX || cycle.len() > boundary.len() {
            return None;
        }
        cycle.push(at);
        at = next[at];
    }
    (cycle.len() == boundary.len() && connected(vertices, triangles)).then_some(cycle)
}

fn connected(vertices: usize, triangles: &[[usize; 3]]) -> bool {
    let mut sets = DisjointSets::<u32>::new(vertices);
    for t in triangles {
        sets.union(t[0], t[1]);
        sets.union(t[1], t[2]);
    }
    (0..vertices).all(|v| sets.find(v) == sets.find(0))
}

/// The area-weighted mean normal, `None` for a disk of no area.
fn mean_normal(vertices: &[CubeVertex], triangles: &[[usize; 3]]) -> Option<DVec3> {
    let sum: DVec3 = triangles
        .iter()
        .map(|t| {
            let p = t.map(|i| vertices[i].pos);
            (p[1] - p[0]).cross(p[2] - p[0])
        })
        .sum();
    let n = sum.normalize_or_zero();
    (n != DVec3::ZERO).then_some(n)
}

fn coord(p: DVec2) -> Coord<f64> {
    Coord { x: p.x, y: p.y }
}

/// Whether the closed polygon `p` runs counter-clockwise and no two of its
/// edges meet but consecutive ones at their shared end.
fn simple_ccw(p: &[DVec2]) -> bool {
    let n = p.len();
    if n < 3 {
        return false;
    }
    let area: f64 = (0..n).map(|i| p[i].perp_dot(p[(i + 1) % n])).sum();
    if area <= 0.0 {
        return false;
    }
    for i in 0..n {
        for j in i + 1..n {
            let adjacent = j == i + 1 || (i == 0 && j == n - 1);
            let (a, b) = (p[i], p[(i + 1) % n]);
            let (c, d) = (p[j], p[(j + 1) % n]);
            if adjacent {
                // Consecutive edges must not fold back onto each other.
                let (s, q, r) = if j == i + 1 { (a, b, d) } else { (c, a, b) };
                if orient2d(coord(s), coord(q), coord(r)) == 0.0 && (r - q).dot(s - q) > 0.0 {
                    return false;
                }
            } else if segments_meet2(coord(a), coord(b), coord(c), coord(d)) {
                return false;
            }
        }
    }
    true
}

/// Ear clipping of the simple counter-clockwise polygon `flat` (vertex ids
/// `ids`): each step cuts the ear of largest `quality` among those strictly
/// convex, holding no other vertex, and whose new edge is not `barred`;
/// `None` if none is left before the last triangle.
fn clip_ears(
    flat: &[DVec2],
    ids: &[usize],
    barred: impl Fn(usize, usize) -> bool,
    quality: impl Fn([usize; 3]) -> f64,
) -> Option<Vec<[usize; 3]>> {
    let mut ring: Vec<usize> = (0..flat.len()).collect();
    let mut out = Vec::with_capacity(flat.len().saturating_sub(2));
    let ear_at = |ring: &[usize], k: usize| -> Option<f64> {
        let n = ring.len();
        let (p, i, q) = (ring[(k + n - 1) % n], ring[k], ring[(k + 1) % n]);
        if barred(ids[p], ids[q]) {
            return None;
        }
        let (a, b, c) = (coord(flat[p]), coord(flat[i]), coord(flat[q]));
        if orient2d(a, b, c) <= 0.0 {
            return None;
        }
        let holds = ring.iter().any(|&r| {
            r != p && r != i && r != q && {
                let x = coord(flat[r]);
                orient2d(a, b, x) >= 0.0 && orient2d(b, c, x) >= 0.0 && orient2d(c, a, x) >= 0.0
            }
        });
        (!holds).then(|| quality([ids[p], ids[i], ids[q]]))
    };
    let mut ears: Vec<Option<f64>> = (0..ring.len()).map(|k| ear_at(&ring, k)).collect();
    let best_of = |ears: &[Option<f64>]| {
        ears.iter()
            .enumerate()
            .filter_map(|(k, e)| e.map(|q| (k, q)))
            .fold(None, |best: Option<(usize, f64)>, (k, q)| match best {
                Some((_, bq)) if bq >= q => best,
                _ => Some((k, q)),
            })
    };
    while ring.len() > 3 {
        let best = match best_of(&ears) {
            Some(b) => b.0,
            None => {
                // A cut vertex may have blocked ears not next to it.
                ears = (0..ring.len()).map(|k| ear_at(&ring, k)).collect();
                best_of(&ears)?.0
            }
        };
        let n = ring.len();
        let (p, i, q) = (ring[(best + n - 1) % n], ring[best], ring[(best + 1) % n]);
        out.push([ids[p], ids[i], ids[q]]);
        ring.remove(best);
        ears.remove(best);
        let n = ring.len();
        let before = (best + n - 1) % n;
        let after = best % n;
        ears[before] = ear_at(&ring, before);
        ears[after] = ear_at(&ring, after);
    }
    let last = [ring[0], ring[1], ring[2]];
    if orient2d(
        coord(flat[last[0]]),
        coord(flat[last[1]]),
        coord(flat[last[2]]),
    ) <= 0.0
    {
        return None;
    }
    out.push(last.map(|r| ids[r]));
    Some(out)
}

/// The smallest angle of triangle `p`, in radians (0 if degenerate).
fn min_angle(p: [DVec3; 3]) -> f64 {
    (0..3)
        .map(|k| {
            let (a, b, c) = (p[k], p[(k + 1) % 3], p[(k + 2) % 3]);
            let (u, v) = (b - a, c - a);
            let (lu, lv) = (u.length(), v.length());
            if lu == 0.0 || lv == 0.0 {
                0.0
            } else {
                (u.dot(v) / (lu * lv)).clamp(-1.0, 1.0).acos()
            }
        })
        .fold(f64::INFINITY, f64::min)
}

#[cfg(test)]
mod tests {
    use super::super::cubes::CORNERS;
    use super::super::lattice::{edge_key, Lattice};
    use super::super::polygonize::polygonize_cube;
    use super::*;

    /// Marching cubes of `f` over the cubes `[0, n)^3`.
    fn march(n: i64, f: impl Fn(DVec3) -> f64) -> Vec<Triangle> {
        let lattice = Lattice::new(DVec3::ZERO, 1.0).expect("lattice");
        let mut out = Vec::new();
        for x in 0..n {
            for y in 0..n {
                for z in 0..n {
                    let values = CORNERS.map(|o| f(lattice.corner([x + o[0], y + o[1], z + o[2]])));
                    polygonize_cube(&lattice, [x, y, z], &values, &mut out).expect("cube");
                }
            }
        }
        out
    }

    /// Boundary edges (as key pairs, in winding order) of a triangle list.
    fn rim(tris: &[Triangle]) -> Vec<(u64, u64)> {
        let edges: Vec<(u64, u64)> = tris
            .iter()
            .flat_map(|t| {
                [
                    (t[0].key, t[1].key),
                    (t[1].key, t[2].key),
                    (t[2].key, t[0].key),
                ]
            })
            .collect();
        let mut rim: Vec<(u64, u64)> = edges
            .iter()
            .copied()
            .filter(|&(a, b)| !edges.contains(&(b, a)))
            .collect();
        rim.sort_unstable();
        rim
    }

    #[test]
    fn a_tilted_plane_loses_triangles_but_not_its_rim_or_its_place() {
        let normal = DVec3::new(0.2, -0.3, 1.0).normalize();
        let plane = |p: DVec3| (p - DVec3::splat(4.1)).dot(normal);
        let fine = march(8, plane);
        let merged = merge_flat_blocks(fine.clone(), 1e-6).expect("merge");
        assert!(
            merged.len() * 2 < fine.len() + 16,
            "{} of {}",
            merged.len(),
            fine.len()
        );
        assert_eq!(rim(&merged), rim(&fine));
        for t in &merged {
            for v in t {
                assert!(plane(v.pos).abs() < 1e-9);
            }
            let n = (t[1].pos - t[0].pos).cross(t[2].pos - t[0].pos);
            assert!(n.dot(normal) > 0.0, "a merged triangle turned over");
            // Every triangle stays within one block.
            let blocks: Vec<[i64; 3]> = t
                .iter()
                .map(|v| block_of(edge_from_key(v.key).expect("key").0))
                .collect();
            let spread = (0..3).all(|a| {
                let (lo, hi) = blocks
                    .iter()
                    .fold((i64::MAX, i64::MIN), |m, b| (m.0.min(b[a]), m.1.max(b[a])));
                hi - lo <= 1
            });
            assert!(spread);
        }
    }

    #[test]
    fn a_tight_sphere_keeps_every_triangle_under_a_small_tolerance() {
        let sphere = |p: DVec3| p.distance(DVec3::splat(4.05)) - 2.7;
        let fine = march(8, sphere);
        let merged = merge_flat_blocks(fine.clone(), 1e-3).expect("merge");
        assert_eq!(merged.len(), fine.len());
        let loose = merge_flat_blocks(fine.clone(), 10.0).expect("merge");
        // However loose, a block bent past the tilt is kept.
        assert!(loose.len() >= fine.len() / 3);
        assert_eq!(rim(&loose), rim(&fine));
    }

    #[test]
    fn faces_name_the_block_sides_an_edge_lies_on() {
        let key = |c: [i64; 3], a: u8| edge_key(c, a).expect("key");
        assert_eq!(faces_of([0, 0, 0], key([1, 2, 3], 0)), Some(0));
        assert_eq!(faces_of([0, 0, 0], key([1, 0, 3], 0)), Some(1 << 2));
        assert_eq!(
            faces_of([0, 0, 0], key([1, 4, 4], 0)),
            Some((1 << 3) | (1 << 5))
        );
        assert_eq!(faces_of([1, 0, 0], key([1, 2, 3], 0)), None);
    }

    #[test]
    fn only_one_disk_has_a_loop() {
        // A square of two triangles, then the same with one apart.
        let square = [[0, 1, 2], [0, 2, 3]];
        assert_eq!(boundary_loop(4, &square).map(|l| l.len()), Some(4));
        assert_eq!(boundary_loop(6, &[[0, 1, 2], [3, 4, 5]]), None);
        // Both windings of one triangle: a closed (two-sided) piece.
        assert_eq!(boundary_loop(3, &[[0, 1, 2], [0, 2, 1]]), None);
    }
}
