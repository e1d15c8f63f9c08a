//! Dropping small pieces: at most [`MAX_PIECE`] triangles joined to each
//! other by edges, and to the rest of the surface at most at vertices.
//! Deviation from paper 4 (its deletions only look at incompatible
//! edges): a triangle laid across the surface whose edges are no surface
//! edges is compatible with everything, so the deletions keep it, and it
//! leaves a non-manifold vertex at each corner and a boundary loop
//! (measured on a 20k sphere, noise 0.05 spacings: one lone triangle and
//! one lone pair, 6 non-manifold vertices, 2 loops); and the noise of a
//! scan closes small bubbles off the surface (1M dragon, noise 0.1
//! spacings: 16 pieces of 1 to 23 triangles beside the dragon). A piece
//! of a dozen points is no surface a scan can show.
//!
//! In tiles, [`piece_doubt`] says which triangles' fate a tile cannot
//! know. Also here: dropping the extra fans of a non-manifold vertex
//! ([`drop_extra_fans`]).

use std::collections::BTreeMap;

/// Largest piece dropped, in triangles.
pub const MAX_PIECE: usize = 24;

fn find(parent: &mut [u32], mut x: u32) -> u32 {
    while parent[x as usize] != x {
        let up = parent[parent[x as usize] as usize];
        parent[x as usize] = up;
        x = up;
    }
    x
}

/// `tris` without the extra fans of its non-manifold vertices: at a vertex
/// whose triangles make more than one fan (edge-connected around it), all
/// but the largest fan (ties: the one holding the smallest triangle) are
/// dropped. Deviation from paper 4, measured on a 20k sphere with noise
/// 0.05 spacings: a vertex whose own disc is whole also closes a triangular
/// hole next to it with a tent of three triangles, or hangs one triangle
/// into a gap; the hole the dropped fan leaves is closed by
/// [`super::holes`]. Reads one ring.
pub fn drop_extra_fans(tris: &[[u32; 3]]) -> Vec<[u32; 3]> {
    let mut at: Vec<(u32, u32)> = tris
        .iter()
        .enumerate()
        .flat_map(|(t, c)| c.map(|v| (v, t as u32)))
        .collect();
    at.sort_unstable();
    let mut drop = vec![false; tris.len()];
    // Buffers kept from vertex to vertex (their allocations were most of
    // this pass's time).
    let (mut parent, mut by_other, mut roots) = (Vec::new(), Vec::new(), Vec::new());
    for group in at.chunk_by(|x, y| x.0 == y.0) {
        let v = group[0].0;
        let t_at = |k: usize| group[k].1;
        // Fans: triangles around v joined by an edge through v.
        parent.clear();
        parent.extend(0..group.len() as u32);
        by_other.clear();
        for k in 0..group.len() {
            for &u in &tris[t_at(k) as usize] {
                if u == v {
                    continue;
                }
                if let Some(&(_, j)) = by_other.iter().find(|o: &&(u32, u32)| o.0 == u) {
                    let (a, b) = (find(&mut parent, j), find(&mut parent, k as u32));
                    parent[a.max(b) as usize] = a.min(b);
                } else {
                    by_other.push((u, k as u32));
                }
            }
        }
        roots.clear();
        roots.extend((0..group.len() as u32).map(|k| find(&mut parent, k)));
        // The first triangle is its fan's root: one fan when all are its.
        if roots.iter().all(|&r| r == 0) {
            continue;
        }
        let mut sizes: BTreeMap<u32, usize> = BTreeMap::new();
        for &r in &roots {
            *sizes.entry(r).or_default() += 1;
        }
        // The root is the fan's first triangle (smallest by tris order).
        let keep = sizes
            .iter()
            .max_by_key(|(&r, &n)| (n, std::cmp::Reverse(tris[t_at(r as usize) as usize])))
            .map(|(&r, _)| r);
        for (k, &r) in roots.iter().enumerate() {
            if Some(r) != keep {
                drop[t_at(k) as usize] = true;
            }
        }
    }
    tris.iter()
        .zip(&drop)
        .filter(|(_, &d)| !d)
        .map(|(t, _)| *t)
        .collect()
}

/// `tris` without its pieces of at most [`MAX_PIECE`] triangles (order
/// kept).
pub fn drop_small_pieces(tris: &[[u32; 3]]) -> Vec<[u32; 3]> {
    let mut parent: Vec<u32> = (0..tris.len() as u32).collect();
    let mut on_edge: Vec<(u64, u32)> = tris
        .iter()
        .enumerate()
        .flat_map(|(t, c)| {
            [(c[0], c[1]), (c[1], c[2]), (c[0], c[2])]
                .map(|(a, b)| ((a.min(b) as u64) << 32 | a.max(b) as u64, t as u32))
        })
        .collect();
    on_edge.sort_unstable();
    for pair in on_edge.windows(2) {
        if pair[0].0 == pair[1].0 {
            let (rs, rt) = (find(&mut parent, pair[0].1), find(&mut parent, pair[1].1));
            parent[rs.max(rt) as usize] = rs.min(rt);
        }
    }
    let roots: Vec<u32> = (0..tris.len() as u32)
        .map(|t| find(&mut parent, t))
        .collect();
    let mut size = vec![0usize; tris.len()];
    for &r in &roots {
        size[r as usize] += 1;
    }
    tris.iter()
        .zip(&roots)
        .filter(|(_, &r)| size[r as usize] > MAX_PIECE)
        .map(|(t, _)| *t)
        .collect()
}

/// Marks doubtful the corners of every triangle of `tris` whose fate in
/// [`drop_small_pieces`] may differ from the whole cloud's, given `doubt`
/// closed (a triangle the cloud has and this tile lacks, or the reverse,
/// has all corners doubtful). A triangle with no doubtful corner is
/// *clean*; a walk from a clean triangle over clean triangles sees what
/// the cloud's walk sees until it meets a triangle with a doubtful corner.
/// So a clean triangle's fate is certain when its clean piece is larger
/// than [`MAX_PIECE`] (kept either way) or is a whole piece touching no
/// other triangle (the same piece either way). This replaces
/// `MAX_PIECE + 2` rings of doubt (about 60 spacings on a noisy scan) by
/// the few a surface needs to hold `MAX_PIECE` triangles.
pub fn piece_doubt(tris: &[[u32; 3]], doubt: &mut [bool]) {
    let clean: Vec<bool> = tris
        .iter()
        .map(|c| c.iter().all(|&v| !doubt[v as usize]))
        .collect();
    let mut keyed: Vec<(u64, u32)> = Vec::with_capacity(3 * tris.len());
    for (t, c) in tris.iter().enumerate() {
        for (a, b) in [(c[0], c[1]), (c[1], c[2]), (c[0], c[2])] {
            keyed.push(((a.min(b) as u64) << 32 | a.max(b) as u64, t as u32));
        }
    }
    keyed.sort_unstable();
    let mut parent: Vec<u32> = (0..tris.len() as u32).collect();
    let mut touches = vec![false; tris.len()];
    for edge in keyed.chunk_by(|x, y| x.0 == y.0) {
        let mut ok = edge.iter().map(|e| e.1).filter(|&t| clean[t as usize]);
        let first = ok.next();
        if let Some(f) = first {
            for t in ok.clone() {
                let (ra, rb) = (find(&mut parent, f), find(&mut parent, t));
                parent[ra.max(rb) as usize] = ra.min(rb);
            }
        }
        if edge.iter().any(|e| !clean[e.1 as usize]) {
            for t in first.into_iter().chain(ok) {
                touches[t as usize] = true;
            }
        }
    }
    // Per clean piece (by root): its triangles, and whether it touches one
    // with a doubtful corner.
    let mut piece = vec![(0usize, false); tris.len()];
    for t in 0..tris.len() as u32 {
        if clean[t as usize] {
            let p = &mut piece[find(&mut parent, t) as usize];
            p.0 += 1;
            p.1 |= touches[t as usize];
        }
    }
    let seeds = doubt.to_vec();
    for (t, c) in tris.iter().enumerate() {
        let uncertain = if clean[t] {
            let (n, touching) = piece[find(&mut parent, t as u32) as usize];
            n <= MAX_PIECE && touching
        } else {
            c.iter().any(|&v| seeds[v as usize])
        };
        if uncertain {
            for &v in c {
                doubt[v as usize] = true;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The triangles of a `w` x `w` vertex grid.
    fn grid(w: u32) -> Vec<[u32; 3]> {
        let mut tris = Vec::new();
        for y in 0..w - 1 {
            for x in 0..w - 1 {
                let (a, b, c, d) = (y * w + x, y * w + x + 1, y * w + x + w, y * w + x + w + 1);
                tris.extend([[a, b, d], [a, c, d]]);
            }
        }
        tris
    }

    /// A 5x5 vertex grid (32 triangles) with a triangle across it (corners
    /// on three grid vertices, edges no grid edge) and a lone triangle
    /// elsewhere: both go, the grid stays.
    #[test]
    fn a_triangle_across_a_surface_is_dropped() {
        let big = grid(5);
        let mut with_lone = big.clone();
        with_lone.extend([[40, 41, 42], [0, 4, 20]]);
        assert_eq!(drop_small_pieces(&with_lone), big);
    }

    /// A vertex of a grid that also makes a tent of three triangles over
    /// a triangular hole elsewhere keeps its own disc only.
    #[test]
    fn the_smaller_fan_of_a_pinched_vertex_is_dropped() {
        let grid = grid(4);
        // Vertex 5's disc is whole; the tent joins it to 20, 21, 22.
        let tent = [[5, 20, 21], [5, 21, 22], [5, 20, 22]];
        let mut tris = grid.clone();
        tris.extend(tent);
        assert_eq!(drop_extra_fans(&tris), grid);
        // Without a second fan nothing changes.
        assert_eq!(drop_extra_fans(&grid), grid);
    }
}
