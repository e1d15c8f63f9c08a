//! Marching cubes on the global lattice (paper 1 section 2.6): one cube at a
//! time by table lookup, vertices keyed by lattice edge and placed by linear
//! interpolation computed the same way from every cube that shares the edge;
//! plus a reference driver that welds a whole set of cubes by key.

use std::collections::HashMap;

use glam::DVec3;

use super::lattice::{edge_key, Lattice, LatticeError};
use super::mc_table::{self, CORNER_OFFSETS, EDGE_AXIS, EDGE_CORNERS};

/// A surface vertex on a lattice edge: the edge's key and the crossing point.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CubeVertex {
    /// The lattice edge the vertex lies on ([`edge_key`]).
    pub key: u64,
    /// Where the field crosses zero on that edge.
    pub pos: DVec3,
}

/// A welded mesh. `keys[i]` is the lattice edge of `vertices[i]`; vertices
/// are in order of first appearance; triangle normals point to f > 0.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct IndexedMesh {
    /// Vertex positions, in order of first appearance.
    pub vertices: Vec<DVec3>,
    /// The lattice edge of each vertex.
    pub keys: Vec<u64>,
    /// Triangles as indices into `vertices`, wound so their normals point to f > 0.
    pub triangles: Vec<[u32; 3]>,
}

/// Appends the triangles of cube `cell` to `out`. `values[c]` is the field at
/// corner `c` of the cube (numbering in [`mc_table`]); "positive" is f > 0.
/// Values must be finite. No allocation besides growing `out`.
pub fn polygonize_cube(
    lattice: &Lattice,
    cell: [i64; 3],
    values: &[f64; 8],
    out: &mut Vec<[CubeVertex; 3]>,
) -> Result<(), LatticeError> {
    if let Some((corner, &value)) = values.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(LatticeError::NonFiniteValue {
            cell,
            corner,
            value,
        });
    }
    let case = mc_table::table()?.case(mc_table::case_index(values));
    let tris = case.triangles();
    if tris.is_empty() {
        return Ok(());
    }
    let mut verts = [CubeVertex {
        key: 0,
        pos: DVec3::ZERO,
    }; 12];
    for (e, v) in verts.iter_mut().enumerate() {
        if case.cut_edges() & (1 << e) != 0 {
            *v = edge_vertex(lattice, cell, e, values)?;
        }
    }
    out.extend(tris.iter().map(|t| t.map(|e| verts[usize::from(e)])));
    Ok(())
}

/// The crossing on cube edge `e`. Canonical: always from the edge's lower
/// lattice corner to its upper one, `t = f0 / (f0 - f1)`, so the four cubes
/// around the edge produce the same bits.
fn edge_vertex(
    lattice: &Lattice,
    cell: [i64; 3],
    e: usize,
    values: &[f64; 8],
) -> Result<CubeVertex, LatticeError> {
    let [lo, hi] = EDGE_CORNERS[e];
    let axis = EDGE_AXIS[e];
    let c0 = offset_corner(cell, lo)?;
    let key = edge_key(c0, axis)?;
    let a = usize::from(axis);
    let mut c1 = c0;
    // c0 is inside the key range, far from i64 overflow.
    c1[a] += 1;
    let (p0, p1) = (lattice.corner(c0), lattice.corner(c1));
    let (f0, f1) = (values[lo], values[hi]);
    // One sign is > 0 and the other <= 0, so f0 - f1 != 0 and t is in [0, 1].
    let t = f0 / (f0 - f1);
    let mut pos = p0;
    pos[a] = p0[a] + t * (p1[a] - p0[a]);
    Ok(CubeVertex { key, pos })
}

/// Lattice index of corner `c` of cube `cell`.
fn offset_corner(cell: [i64; 3], c: usize) -> Result<[i64; 3], LatticeError> {
    let off = CORNER_OFFSETS[c];
    let add = |i: usize| cell[i].checked_add(off[i]);
    match (add(0), add(1), add(2)) {
        (Some(x), Some(y), Some(z)) => Ok([x, y, z]),
        _ => Err(LatticeError::OutOfRange { cell }),
    }
}

/// Welds cube triangles into an [`IndexedMesh`] by edge key, vertices in
/// first-appearance order (deterministic: the map is never iterated).
#[derive(Debug, Default)]
pub struct MeshWelder {
    index: HashMap<u64, u32>,
    mesh: IndexedMesh,
}

impl MeshWelder {
    pub(crate) fn new() -> Self {
        Self::default()
    }

    pub(crate) fn push(&mut self, tri: &[CubeVertex; 3]) -> Result<(), LatticeError> {
        let mut ids = [0u32; 3];
        for (id, v) in ids.iter_mut().zip(tri) {
            *id = self.vertex_id(v)?;
        }
        self.mesh.triangles.push(ids);
        Ok(())
    }

    fn vertex_id(&mut self, v: &CubeVertex) -> Result<u32, LatticeError> {
        if let Some(&id) = self.index.get(&v.key) {
            return Ok(id);
        }
        let id =
            u32::try_from(self.mesh.vertices.len()).map_err(|_| LatticeError::TooManyVertices)?;
        self.index.insert(v.key, id);
        self.mesh.vertices.push(v.pos);
        self.mesh.keys.push(v.key);
        Ok(id)
    }

    pub(crate) fn finish(self) -> IndexedMesh {
        self.mesh
    }
}

/// Reference driver: polygonises `cells` in the given order with the field
/// `f`, evaluated at lattice corners. A cube with any undefined corner
/// (`None`) emits nothing, which leaves open boundaries (paper 1 step 6).
/// Corners shared by several cubes are evaluated once per cube, so `f` must
/// be deterministic.
pub fn polygonize_field<I, F>(
    lattice: &Lattice,
    cells: I,
    f: F,
) -> Result<IndexedMesh, LatticeError>
where
    I: IntoIterator<Item = [i64; 3]>,
    F: Fn(DVec3) -> Option<f64>,
{
    let mut welder = MeshWelder::new();
    let mut tris = Vec::with_capacity(mc_table::MAX_TRIANGLES);
    for cell in cells {
        let Some(values) = corner_values(lattice, cell, &f)? else {
            continue;
        };
        tris.clear();
        polygonize_cube(lattice, cell, &values, &mut tris)?;
        for t in &tris {
            welder.push(t)?;
        }
    }
    Ok(welder.finish())
}

/// The field at the 8 corners of `cell`, or `None` if any is undefined.
fn corner_values<F>(
    lattice: &Lattice,
    cell: [i64; 3],
    f: &F,
) -> Result<Option<[f64; 8]>, LatticeError>
where
    F: Fn(DVec3) -> Option<f64>,
{
    let mut values = [0.0; 8];
    for (c, v) in values.iter_mut().enumerate() {
        match f(lattice.corner(offset_corner(cell, c)?)) {
            Some(x) => *v = x,
            None => return Ok(None),
        }
    }
    Ok(Some(values))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lone_positive_corner_gives_one_triangle_facing_it() {
        let lat = Lattice::new(DVec3::new(0.5, -2.0, 3.0), 0.25).unwrap();
        let mut values = [-1.0; 8];
        values[0] = 1.0;
        let mut out = Vec::new();
        polygonize_cube(&lat, [4, -3, 7], &values, &mut out).unwrap();
        assert_eq!(out.len(), 1);
        let [a, b, c] = out[0].map(|v| v.pos);
        let n = (b - a).cross(c - a);
        // The positive corner is the cube's min corner: the normal points there.
        assert!(n.dot(lat.corner([4, -3, 7]) - a) > 0.0, "{n:?}");
        for v in out[0] {
            let mid = (v.pos - lat.corner([4, -3, 7])) / lat.cell;
            assert!((mid.element_sum() - 0.5).abs() < 1e-12, "{mid:?}");
        }
    }

    #[test]
    fn non_finite_values_and_out_of_range_cells_are_errors() {
        let lat = Lattice::new(DVec3::ZERO, 1.0).unwrap();
        let mut out = Vec::new();
        let mut values = [-1.0; 8];
        values[3] = f64::NAN;
        let r = polygonize_cube(&lat, [0; 3], &values, &mut out);
        assert!(matches!(
            r,
            Err(LatticeError::NonFiniteValue { corner: 3, .. })
        ));
        values[3] = 1.0;
        let far = [i64::MAX, 0, 0];
        assert!(matches!(
            polygonize_cube(&lat, far, &values, &mut out),
            Err(LatticeError::OutOfRange { .. })
        ));
        assert!(out.is_empty());
    }
}
