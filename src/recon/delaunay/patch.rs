//! Triangulating one small hole (a loop found by [`super::holes`]) so
//! that it neither folds nor cuts the surface. The measure is Liepa's
//! (*Filling holes in meshes*, 2003): the least worst fold, then the least
//! area, by dynamic programming over the polygon, each sub-polygon's best
//! triangulation judged by its triangle on the chord. A fold is an edge
//! where two triangles make an acute dihedral angle (paper 4 section 2.3's
//! incompatibility), between two patch triangles or between a patch
//! triangle and the surface triangle across a loop edge; it is measured by
//! the cosine of the angle, so a patch without folds is the least-area one.
//! A patch that still crosses a triangle around the loop is refused.
//!
//! Least area alone folded patches over their rim on the noisy dragon (879
//! acute edges and 122 self-intersecting pairs on 327k points, none
//! without the patches); refusing every fold left 1,367 holes open, most
//! of them three-edge holes whose one fold is near square (median cosine
//! 0.12), with no crossing.

use super::cleanup::across;
use super::rim::{edge, Edge};
use crate::mesh::intersect::triangles_intersect;
use glam::DVec3;
use std::collections::{BTreeMap, BTreeSet};

pub(crate) fn sorted(mut t: [u32; 3]) -> [u32; 3] {
    t.sort_unstable();
    t
}

/// How far the triangles `(a, b, s)` and `(a, b, t)` on edge `ab` fold
/// onto each other: the cosine of their dihedral angle when it is acute
/// (their apexes on the same side seen along the edge, the test of
/// [`super::cleanup::Cleanup::acute`]), else 0.
fn fold(points: &[DVec3], a: u32, b: u32, s: u32, t: u32) -> f64 {
    let p = |v: u32| points[v as usize];
    let side = |q: u32| across(p(a), p(b), p(q)).normalize_or_zero();
    side(s).dot(side(t)).max(0.0)
}

/// A sub-polygon's triangulation measure: worst fold, then area.
#[derive(Clone, Copy, PartialEq, PartialOrd)]
struct Measure(f64, f64);

const NONE: Measure = Measure(f64::INFINITY, f64::INFINITY);

/// The triangulation of polygon `c` of least worst fold, then least area,
/// whose diagonals are not edges of the surface yet and whose triangles
/// are not `known` (the boundary of a lone triangle is a 3-cycle, not a
/// hole); `outer[k]` is the apex of the surface triangle on edge `c[k],
/// c[k + 1]` (the last closes the polygon). None if there is none.
pub fn least_fold_patch(
    points: &[DVec3],
    c: &[u32],
    outer: &[u32],
    order: &BTreeMap<Edge, u32>,
    known: &BTreeSet<[u32; 3]>,
) -> Option<Vec<[u32; 3]>> {
    let n = c.len();
    let p = |k: usize| points[c[k] as usize];
    let free = |i: usize, j: usize| {
        j == i + 1 || (i == 0 && j == n - 1) || { !order.contains_key(&edge(c[i], c[j])) }
    };
    // cost[i][j]: the polygon i..=j closed by chord ij; split[i][j]: apex.
    let mut cost = vec![vec![NONE; n]; n];
    let mut split = vec![vec![usize::MAX; n]; n];
    for i in 0..n - 1 {
        cost[i][i + 1] = Measure(0.0, 0.0);
    }
    // The apex across chord ij from the side of the polygon i..=j.
    let beyond = |split: &[Vec<usize>], i: usize, j: usize| {
        if j == i + 1 {
            outer[i]
        } else {
            c[split[i][j]]
        }
    };
    for len in 2..n {
        for i in 0..n - len {
            let j = i + len;
            if !free(i, j) {
                continue;
            }
            for m in i + 1..j {
                let (left, right) = (cost[i][m], cost[m][j]);
                if left == NONE || right == NONE || known.contains(&sorted([c[i], c[m], c[j]])) {
                    continue;
                }
                let mut worst = left.0.max(right.0);
                worst = worst.max(fold(points, c[i], c[m], c[j], beyond(&split, i, m)));
                worst = worst.max(fold(points, c[m], c[j], c[i], beyond(&split, m, j)));
                if len == n - 1 {
                    worst = worst.max(fold(points, c[i], c[j], c[m], outer[n - 1]));
                }
                let area = 0.5 * (p(m) - p(i)).cross(p(j) - p(i)).length();
                let total = Measure(worst, left.1 + right.1 + area);
                if total < cost[i][j] {
                    cost[i][j] = total;
                    split[i][j] = m;
                }
            }
        }
    }
    if cost[0][n - 1] == NONE {
        return None;
    }
    let mut out = Vec::with_capacity(n - 2);
    let mut stack = vec![(0, n - 1)];
    while let Some((i, j)) = stack.pop() {
        if j <= i + 1 {
            continue;
        }
        let m = split[i][j];
        out.push(sorted([c[i], c[m], c[j]]));
        stack.push((i, m));
        stack.push((m, j));
    }
    Some(out)
}

/// Whether a triangle of `patch` crosses another of `patch` or one of
/// `around` (exactly, beyond what the two share; see
/// [`crate::mesh::intersect`]).
pub fn crosses(points: &[DVec3], patch: &[[u32; 3]], around: &[[u32; 3]]) -> bool {
    let at = |t: [u32; 3]| t.map(|v| points[v as usize]);
    patch.iter().enumerate().any(|(k, &t)| {
        patch[k + 1..]
            .iter()
            .chain(around)
            .any(|&o| triangles_intersect(t, &at(t), o, &at(o)))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A quadrilateral hole with corner 2 below the plane of the others,
    /// whose rim triangle on edge 01 stands up over the hole: the diagonal
    /// 1-3 is the smaller area, but its triangle 0,1,3 would fold onto
    /// that rim triangle, so the patch takes the diagonal 0-2.
    #[test]
    fn the_patch_avoids_a_fold_least_area_would_make() {
        let points = vec![
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(1.2, 1.2, -0.6),
            DVec3::new(0.0, 1.0, 0.0),
            // Apex of the rim triangle on 01: over the hole, nearly upright.
            DVec3::new(0.5, 0.2, 1.0),
            // Apexes of the other rim triangles, outside the hole.
            DVec3::new(2.0, 0.6, 0.0),
            DVec3::new(0.6, 2.0, 0.0),
            DVec3::new(-1.0, 0.5, 0.0),
        ];
        let cycle = [0, 1, 2, 3];
        let outer = [4, 5, 6, 7];
        let (order, known) = (BTreeMap::new(), BTreeSet::new());
        let patch = least_fold_patch(&points, &cycle, &outer, &order, &known).unwrap();
        let mut got = patch.clone();
        got.sort_unstable();
        assert_eq!(got, vec![[0, 1, 2], [0, 2, 3]]);
        assert!(
            fold(&points, 0, 1, 3, 4) > 0.0,
            "the other diagonal would fold"
        );
        let area = |a: usize, b: usize, c: usize| {
            (points[b] - points[a])
                .cross(points[c] - points[a])
                .length()
        };
        assert!(area(0, 1, 3) + area(1, 2, 3) < area(0, 1, 2) + area(0, 2, 3));
    }

    /// A patch triangle crossing a triangle near it is seen; one beside it
    /// is not, nor one sharing an edge flat with it.
    #[test]
    fn crossings_are_found_exactly() {
        let points = vec![
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
            DVec3::new(0.2, 0.2, -1.0),
            DVec3::new(0.2, 0.2, 1.0),
            DVec3::new(0.9, 0.9, 1.0),
            DVec3::new(1.0, 1.0, 0.0),
        ];
        let patch = [[0, 1, 2]];
        assert!(crosses(&points, &patch, &[[3, 4, 5]]));
        assert!(!crosses(&points, &patch, &[[4, 5, 6]]));
        assert!(!crosses(&points, &patch, &[[1, 2, 6]]));
    }
}
