//! The marching-cubes case table (paper 1 section 2.6: a corner with f > 0 is
//! 1, else 0; the 8 bits index the table), generated in code by face walking
//! rather than copied.
//!
//! # Numbering
//! Corner `c` (0..8) sits at offset `(c & 1, (c >> 1) & 1, (c >> 2) & 1)` from
//! the cube's min corner; bit `c` of the case index is set when `f > 0` there.
//!
//! Edge `e = 4 * axis + k` runs along `axis` from its lower corner to its
//! upper corner; `k` gives the other two coordinates (the smaller other axis
//! in bit 0):
//!
//! | edge | corners | edge | corners | edge | corners |
//! |------|---------|------|---------|------|---------|
//! | 0 (x)| 0-1     | 4 (y)| 0-2     | 8 (z)| 0-4     |
//! | 1 (x)| 2-3     | 5 (y)| 1-3     | 9 (z)| 1-5     |
//! | 2 (x)| 4-5     | 6 (y)| 4-6     | 10 (z)| 2-6    |
//! | 3 (x)| 6-7     | 7 (y)| 5-7     | 11 (z)| 3-7    |
//!
//! Face `2 * axis + side` is the cube face where the `axis` coordinate equals
//! `side`; its outward normal is `-e_axis` (side 0) or `+e_axis` (side 1).
//!
//! # Construction
//! 1. On each face, the sign-change edges are paired into segments. Two cuts:
//!    one segment. Four cuts (an ambiguous face): each positive corner is cut
//!    off by its own segment, i.e. the positive corners are always separated.
//!    The rule reads only the face's four signs, so the two cubes sharing a
//!    face make the same choice and the surface has no cracks.
//! 2. Each segment is directed so that, seen from outside the cube, the
//!    positive corners are on its left. Every cut edge then starts exactly one
//!    segment and ends one, so the segments chain into closed loops.
//! 3. Each loop is triangulated (the triangulation maximising the smallest
//!    angle, at edge midpoints) using only diagonals between edges that share
//!    no cube face: a diagonal inside a face could be chosen by the neighbour
//!    cube too and would then carry four triangles.
//!
//! Triangles keep the loop's direction, so by the right-hand rule their
//! normals point to the positive side (f > 0 = outside).
//!
//! Deviation: paper 1 follows the small-feature variant of Zhou, Shu and
//! Kankanhalli (1994, its reference \[11\]), which is not restated in the
//! paper. We use this face-consistent construction instead because crack-free
//! seams between tiles need exactly one property, a face rule that reads only
//! the face's signs, and this construction makes that property explicit.

use std::sync::OnceLock;

use glam::I64Vec3;

use super::lattice::LatticeError;

/// Most triangles of any case. The construction yields at most 5 (as the
/// classic table); a case needing more fails the build with an error.
pub(crate) const MAX_TRIANGLES: usize = 5;

/// Offset of each corner from the cube's min corner.
pub const CORNER_OFFSETS: [[i64; 3]; 8] = corner_offsets();
/// (lower corner, upper corner) of each edge.
pub const EDGE_CORNERS: [[usize; 2]; 12] = edge_corners();
/// The axis each edge runs along.
pub const EDGE_AXIS: [u8; 12] = [0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2, 2];

const fn corner_offsets() -> [[i64; 3]; 8] {
    let mut out = [[0i64; 3]; 8];
    let mut c = 0;
    while c < 8 {
        out[c] = [(c & 1) as i64, ((c >> 1) & 1) as i64, ((c >> 2) & 1) as i64];
        c += 1;
    }
    out
}

const fn edge_corners() -> [[usize; 2]; 12] {
    let mut out = [[0usize; 2]; 12];
    let mut e = 0;
    while e < 12 {
        let axis = e / 4;
        let k = e % 4;
        let (u, v) = match axis {
            0 => (1, 2),
            1 => (0, 2),
            _ => (0, 1),
        };
        let lower = ((k & 1) << u) | ((k >> 1) << v);
        out[e] = [lower, lower | (1 << axis)];
        e += 1;
    }
    out
}

/// Triangles of one sign configuration, as edge-index triples.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct McCase {
    len: u8,
    cut_edges: u16,
    tris: [[u8; 3]; MAX_TRIANGLES],
}

impl McCase {
    const EMPTY: McCase = McCase {
        len: 0,
        cut_edges: 0,
        tris: [[0; 3]; MAX_TRIANGLES],
    };

    /// The triangles, each a triple of edge indices, normal toward f > 0.
    pub fn triangles(&self) -> &[[u8; 3]] {
        &self.tris[..usize::from(self.len)]
    }

    /// Bit `e` set when edge `e` changes sign in this case.
    pub(crate) fn cut_edges(&self) -> u16 {
        self.cut_edges
    }
}

/// All 256 cases, indexed by `case_index`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct McTable {
    cases: [McCase; 256],
}

impl McTable {
    /// The triangles of the cube case `index` (bit `c` set when corner `c` is positive).
    pub fn case(&self, index: u8) -> &McCase {
        &self.cases[usize::from(index)]
    }
}

/// The case of a cube: bit `c` set when `values[c] > 0` (NaN counts as not
/// positive; callers reject non-finite values first).
pub(crate) fn case_index(values: &[f64; 8]) -> u8 {
    let mut index = 0u8;
    for (c, &v) in values.iter().enumerate() {
        if v > 0.0 {
            index |= 1 << c;
        }
    }
    index
}

/// The table, built on first use.
pub fn table() -> Result<&'static McTable, LatticeError> {
    static TABLE: OnceLock<Result<McTable, LatticeError>> = OnceLock::new();
    TABLE
        .get_or_init(build_table)
        .as_ref()
        .map_err(Clone::clone)
}

/// Builds the table by the face-walking construction (see the module docs).
pub(crate) fn build_table() -> Result<McTable, LatticeError> {
    let mut cases = [McCase::EMPTY; 256];
    for (index, case) in cases.iter_mut().enumerate() {
        *case = build_case(index)?;
    }
    Ok(McTable { cases })
}

fn build_case(index: usize) -> Result<McCase, LatticeError> {
    let err = |reason| LatticeError::Table {
        case: index,
        reason,
    };
    let positive = |c: usize| index & (1 << c) != 0;
    let mut next: [Option<usize>; 12] = [None; 12];
    for face in 0..6 {
        for [a, b] in face_segments(face, &positive).map_err(err)? {
            if next[a].is_some() {
                return Err(err("a cut edge starts two segments"));
            }
            next[a] = Some(b);
        }
    }
    let mut case = McCase::EMPTY;
    let mut visited = 0u16;
    for start in 0..12 {
        let [lo, hi] = EDGE_CORNERS[start];
        if positive(lo) != positive(hi) {
            case.cut_edges |= 1 << start;
        }
        if next[start].is_none() || visited & (1 << start) != 0 {
            continue;
        }
        let lp = walk_loop(start, &next, &mut visited).map_err(err)?;
        for tri in triangulate_loop(&lp).ok_or(err("loop has no valid triangulation"))? {
            let slot = case
                .tris
                .get_mut(usize::from(case.len))
                .ok_or(err("too many triangles"))?;
            *slot = tri;
            case.len += 1;
        }
    }
    if visited != case.cut_edges {
        return Err(err("segments do not cover exactly the cut edges"));
    }
    Ok(case)
}

/// Follows `next` from `start` until it returns there.
fn walk_loop(
    start: usize,
    next: &[Option<usize>; 12],
    visited: &mut u16,
) -> Result<Vec<u8>, &'static str> {
    let mut lp = Vec::with_capacity(12);
    let mut e = start;
    loop {
        if *visited & (1 << e) != 0 {
            return Err("segments do not close into a loop");
        }
        *visited |= 1 << e;
        lp.push(e as u8);
        e = next[e].ok_or("a cut edge ends no segment")?;
        if e == start {
            return Ok(lp);
        }
    }
}

/// The four corners of `face`.
fn face_corners(face: usize) -> impl Iterator<Item = usize> {
    let (axis, side) = (face / 2, face % 2);
    (0..8).filter(move |c| (c >> axis) & 1 == side)
}

/// The four edges of `face`.
fn face_edges(face: usize) -> impl Iterator<Item = usize> {
    let (axis, side) = (face / 2, face % 2);
    (0..12).filter(move |&e| {
        usize::from(EDGE_AXIS[e]) != axis && (EDGE_CORNERS[e][0] >> axis) & 1 == side
    })
}

/// Bit `f` set for both faces that contain edge `e`.
fn edge_face_mask(e: usize) -> u8 {
    (0..6).fold(0, |m, f| {
        if face_edges(f).any(|x| x == e) {
            m | 1 << f
        } else {
            m
        }
    })
}

/// The directed segments on one face (step 1 and 2 of the construction).
fn face_segments(
    face: usize,
    positive: &impl Fn(usize) -> bool,
) -> Result<Vec<[usize; 2]>, &'static str> {
    let is_cut = |e: &usize| {
        let [lo, hi] = EDGE_CORNERS[*e];
        positive(lo) != positive(hi)
    };
    let cuts: Vec<usize> = face_edges(face).filter(is_cut).collect();
    let mut out = Vec::with_capacity(2);
    match cuts.len() {
        0 => {}
        2 => {
            let p = face_corners(face)
                .find(|&c| positive(c))
                .ok_or("cut face without a positive corner")?;
            out.push(orient(face, cuts[0], cuts[1], p)?);
        }
        4 => {
            for p in face_corners(face).filter(|&c| positive(c)) {
                let mut at_p = cuts
                    .iter()
                    .copied()
                    .filter(|&e| EDGE_CORNERS[e].contains(&p));
                let (a, b) = (at_p.next(), at_p.next());
                let (a, b) = a.zip(b).ok_or("positive corner without two cut edges")?;
                out.push(orient(face, a, b, p)?);
            }
        }
        _ => return Err("odd number of cut edges on a face"),
    }
    Ok(out)
}

/// Directs segment `a`-`b` on `face` so that positive corner `p` is on its
/// left seen from outside: `(n x (m_b - m_a)) . (p - m_a) > 0`, computed
/// exactly in doubled integer coordinates.
fn orient(face: usize, a: usize, b: usize, p: usize) -> Result<[usize; 2], &'static str> {
    let mut n = I64Vec3::ZERO;
    n[face / 2] = if face % 2 == 1 { 1 } else { -1 };
    let (ma, mb) = (edge_midpoint2(a), edge_midpoint2(b));
    let pc = I64Vec3::from_array(CORNER_OFFSETS[p]) * 2;
    match n.cross(mb - ma).dot(pc - ma).signum() {
        1 => Ok([a, b]),
        -1 => Ok([b, a]),
        _ => Err("positive corner on the segment's line"),
    }
}

/// Twice the midpoint of edge `e` in cube coordinates.
fn edge_midpoint2(e: usize) -> I64Vec3 {
    let [lo, hi] = EDGE_CORNERS[e].map(|c| I64Vec3::from_array(CORNER_OFFSETS[c]));
    lo + hi
}

/// Triangulates a loop of cut edges (step 3): interval dynamic programme
/// over the polygon, maximising the smallest angle, diagonals only between
/// edges sharing no face, ties to the lowest split vertex.
fn triangulate_loop(lp: &[u8]) -> Option<Vec<[u8; 3]>> {
    let n = lp.len();
    let pos: Vec<I64Vec3> = lp.iter().map(|&e| edge_midpoint2(usize::from(e))).collect();
    let masks: Vec<u8> = lp.iter().map(|&e| edge_face_mask(usize::from(e))).collect();
    let allowed =
        |i: usize, j: usize| j == i + 1 || (i == 0 && j == n - 1) || masks[i] & masks[j] == 0;
    // best[i][j]: (quality, split) of the sub-polygon i..=j with base edge i-j.
    let mut best = vec![vec![None::<(f64, usize)>; n]; n];
    for len in 2..n {
        for i in 0..n - len {
            let j = i + len;
            best[i][j] = best_split(i, j, &pos, &best, &allowed);
        }
    }
    let mut tris = Vec::with_capacity(n.saturating_sub(2));
    collect_triangles(0, n - 1, lp, &best, &mut tris)?;
    Some(tris)
}

type Splits = Vec<Vec<Option<(f64, usize)>>>;

/// The best apex `k` for base edge `i`-`j`: the quality of a triangulation
/// is its worst triangle's [`angle_quality`].
fn best_split(
    i: usize,
    j: usize,
    pos: &[I64Vec3],
    best: &Splits,
    allowed: &impl Fn(usize, usize) -> bool,
) -> Option<(f64, usize)> {
    let sub = |a: usize, b: usize| {
        if b - a < 2 {
            Some(f64::INFINITY)
        } else {
            best[a][b].map(|s| s.0)
        }
    };
    let mut found: Option<(f64, usize)> = None;
    for k in i + 1..j {
        if !(allowed(i, k) && allowed(k, j)) {
            continue;
        }
        let parts = (angle_quality(pos[i], pos[k], pos[j]), sub(i, k), sub(k, j));
        let (Some(t), Some(l), Some(r)) = parts else {
            continue;
        };
        let q = t.min(l).min(r);
        if found.is_none_or(|(bq, _)| q > bq) {
            found = Some((q, k));
        }
    }
    found
}

fn collect_triangles(
    i: usize,
    j: usize,
    lp: &[u8],
    best: &Splits,
    out: &mut Vec<[u8; 3]>,
) -> Option<()> {
    if j - i < 2 {
        return Some(());
    }
    let (_, k) = best[i][j]?;
    out.push([lp[i], lp[k], lp[j]]);
    collect_triangles(i, k, lp, best, out)?;
    collect_triangles(k, j, lp, best, out)
}

/// Increasing in the triangle's smallest angle: minus the signed squared
/// cosine of that angle; `None` when degenerate. Exact integer inputs and
/// one IEEE division (no libm), so the table is the same on every platform.
fn angle_quality(a: I64Vec3, b: I64Vec3, c: I64Vec3) -> Option<f64> {
    if (b - a).cross(c - a) == I64Vec3::ZERO {
        return None;
    }
    let cos2 = |o: I64Vec3, p: I64Vec3, q: I64Vec3| {
        let (u, v) = (p - o, q - o);
        let d = u.dot(v);
        (d * d.abs()) as f64 / (u.length_squared() * v.length_squared()) as f64
    };
    Some(-cos2(a, b, c).max(cos2(b, c, a)).max(cos2(c, a, b)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbering_matches_the_documented_table() {
        let expected = [
            [0, 1],
            [2, 3],
            [4, 5],
            [6, 7],
            [0, 2],
            [1, 3],
            [4, 6],
            [5, 7],
            [0, 4],
            [1, 5],
            [2, 6],
            [3, 7],
        ];
        assert_eq!(EDGE_CORNERS, expected);
        for e in 0..12 {
            assert_eq!(edge_face_mask(e).count_ones(), 2, "edge {e}");
        }
    }

    #[test]
    fn table_builds_and_cuts_lone_corners_with_one_triangle() {
        let t = table().unwrap();
        assert!(t.case(0).triangles().is_empty());
        assert!(t.case(255).triangles().is_empty());
        // A single positive corner is cut off by one triangle.
        for c in 0..8 {
            assert_eq!(t.case(1 << c).triangles().len(), 1, "corner {c}");
        }
    }
}
