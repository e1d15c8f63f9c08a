//! The brute-force kNN oracle and the one neighbour order every backend uses.
//!
//! The oracle looks at every point, so it is the reference the grid and the
//! kd-tree are tested against; it is deliberately simple (compute all, select the k smallest, sort).

use std::cmp::Ordering;

use glam::DVec3;

use super::Neighbour;

/// The canonical neighbour order: squared distance, then the point's tie key
/// (its global id), then its index in the slice.
///
/// The last key only matters when two points share a tie key, which callers
/// should not allow; it keeps even that case identical across backends.
#[inline]
pub fn neighbour_order(tie: &[u64], a: &Neighbour, b: &Neighbour) -> Ordering {
    a.dist2
        .total_cmp(&b.dist2)
        .then_with(|| tie_of(tie, a.index).cmp(&tie_of(tie, b.index)))
        .then_with(|| a.index.cmp(&b.index))
}

/// The tie key of point `index`; an index without a key (a caller error the
/// index constructors reject) sorts last rather than panicking.
#[inline]
pub(crate) fn tie_of(tie: &[u64], index: u32) -> u64 {
    tie.get(index as usize).copied().unwrap_or(u64::MAX)
}

/// The canonical squared distance: the one formula every backend reports.
#[inline]
pub(crate) fn dist2(p: DVec3, q: DVec3) -> f64 {
    (p - q).length_squared()
}

/// The exact k nearest points to `q` among `points`, skipping `exclude`,
/// sorted by [`neighbour_order`]. O(n + k log k); for tests and tiny inputs.
///
/// Points beyond `u32::MAX` cannot be named by a [`Neighbour`] and are ignored.
pub fn brute_knn(
    points: &[DVec3],
    tie: &[u64],
    q: DVec3,
    k: usize,
    exclude: Option<u32>,
) -> Vec<Neighbour> {
    let mut all: Vec<Neighbour> = points
        .iter()
        .zip(0..=u32::MAX)
        .filter(|&(_, i)| Some(i) != exclude)
        .map(|(p, index)| Neighbour {
            dist2: dist2(*p, q),
            index,
        })
        .collect();
    let order = |a: &Neighbour, b: &Neighbour| neighbour_order(tie, a, b);
    if k == 0 {
        all.clear();
    } else if k < all.len() {
        all.select_nth_unstable_by(k - 1, order);
        all.truncate(k);
    }
    all.sort_by(order);
    all
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equidistant_points_follow_tie_keys() {
        let points = [DVec3::X, DVec3::NEG_X, DVec3::Y, DVec3::ZERO];
        let tie = [30, 10, 20, 40];
        let got = brute_knn(&points, &tie, DVec3::ZERO, 3, Some(3));
        let order: Vec<u32> = got.iter().map(|n| n.index).collect();
        assert_eq!(order, vec![1, 2, 0]);
        assert!(got.iter().all(|n| n.dist2 == 1.0));
    }
}
