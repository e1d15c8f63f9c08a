//! A stream's spacing from exact neighbourhoods, in one pass and in
//! whatever order the file was written (`scanmesh info`).
//!
//! The mean nearest-neighbour distance of a file's first points is the
//! spacing only when the file is written in spatial order (a scanner's
//! lines). A shuffled, generated or octree-ordered file (COPC's root nodes
//! come first) starts with a thin sample of the whole cloud, whose spacing
//! is the cloud's times the square root of the thinning: 39 times too
//! large on 100M points sampled from the dragon. Here a few anchors are
//! taken among the first points, each keeps the points nearest to it in
//! the whole stream, and the nearest-neighbour distances inside those
//! patches are exact at full density, as the store's estimate is
//! (`store::spacing`), whatever the order.

use glam::DVec3;
use std::cmp::Ordering;
use std::collections::BinaryHeap;

/// Points buffered before the anchors are chosen among them; a stream no
/// longer than this is measured whole.
const HEAD: usize = 1 << 16;
/// Anchors, spread over the head in stream order.
const ANCHORS: usize = 16;
/// Points each anchor keeps: about a quarter of them lie within half the
/// patch's radius, where their nearest distances are measured.
const PATCH: usize = 2048;

/// The spacing of the points offered so far, as they stream past.
#[derive(Debug)]
pub struct SpacingPatches {
    head: Vec<DVec3>,
    head_len: usize,
    patch_len: usize,
    patches: Vec<Patch>,
}

impl Default for SpacingPatches {
    fn default() -> Self {
        Self::with_sizes(HEAD, PATCH)
    }
}

impl SpacingPatches {
    /// An estimator that has seen no point.
    pub fn new() -> Self {
        Self::default()
    }

    fn with_sizes(head_len: usize, patch_len: usize) -> Self {
        Self {
            head: Vec::new(),
            head_len,
            patch_len,
            patches: Vec::new(),
        }
    }

    /// Takes the next points of the stream into account.
    pub fn offer(&mut self, points: &[DVec3]) {
        for &p in points {
            if self.patches.is_empty() {
                self.head.push(p);
                if self.head.len() == self.head_len {
                    self.anchor_on_head();
                }
            } else {
                self.patches.iter_mut().for_each(|patch| patch.offer(p));
            }
        }
    }

    /// Mean nearest-neighbour distance (exact duplicates left out: a zero
    /// distance says nothing of the sampling); `None` with fewer than two
    /// distinct points.
    pub fn estimate(&self) -> Option<f64> {
        if self.patches.is_empty() {
            return super::mean_nearest_distance(&self.head);
        }
        let (mut sum, mut n) = (0.0, 0u64);
        for d in self.patches.iter().flat_map(Patch::inner_distances) {
            sum += d;
            n += 1;
        }
        (n > 0).then(|| sum / n as f64)
    }

    fn anchor_on_head(&mut self) {
        let head = std::mem::take(&mut self.head);
        let step = (head.len() / ANCHORS).max(1);
        let len = self.patch_len;
        self.patches = head
            .iter()
            .step_by(step)
            .map(|&a| Patch::new(a, len))
            .collect();
        for &p in &head {
            self.patches.iter_mut().for_each(|patch| patch.offer(p));
        }
    }
}

/// The points nearest to one anchor among those offered.
#[derive(Debug)]
struct Patch {
    anchor: DVec3,
    len: usize,
    near: BinaryHeap<Near>,
}

/// A point and its squared distance to the anchor, farthest on top.
#[derive(Debug)]
struct Near {
    dist2: f64,
    point: DVec3,
}

impl PartialEq for Near {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}
impl Eq for Near {}
impl PartialOrd for Near {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Near {
    fn cmp(&self, other: &Self) -> Ordering {
        self.dist2.total_cmp(&other.dist2)
    }
}

impl Patch {
    fn new(anchor: DVec3, len: usize) -> Self {
        Self {
            anchor,
            len,
            near: BinaryHeap::with_capacity(len + 1),
        }
    }

    fn offer(&mut self, point: DVec3) {
        let dist2 = (point - self.anchor).length_squared();
        if self.near.len() < self.len {
            self.near.push(Near { dist2, point });
        } else if self.near.peek().is_some_and(|far| dist2 < far.dist2) {
            self.near.pop();
            self.near.push(Near { dist2, point });
        }
    }

    /// Nearest distances of the points within half the patch's radius
    /// whose nearest neighbour is surely in the patch: every point the
    /// stream held nearer to the anchor than the radius is kept, so a
    /// neighbour found closer than the rest of the radius is the nearest.
    fn inner_distances(&self) -> Vec<f64> {
        let points: Vec<DVec3> = self.near.iter().map(|n| n.point - self.anchor).collect();
        let whole = self.near.len() < self.len;
        let radius = self.near.peek().map_or(0.0, |far| far.dist2.sqrt());
        let mut out = Vec::new();
        for (i, p) in points.iter().enumerate() {
            let from_anchor = p.length();
            if !whole && from_anchor > radius / 2.0 {
                continue;
            }
            let nearest2 = points
                .iter()
                .enumerate()
                .filter(|&(j, _)| j != i)
                .map(|(_, q)| (*q - *p).length_squared())
                .fold(f64::INFINITY, f64::min);
            let nearest = nearest2.sqrt();
            if nearest > 0.0 && (whole || from_anchor + nearest < radius) {
                out.push(nearest);
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    /// A square grid of `side * side` points at spacing `step`, far from
    /// the origin as projected coordinates are.
    fn grid(side: usize, step: f64) -> Vec<DVec3> {
        let origin = DVec3::new(512_000.0, 5_400_000.0, 300.0);
        (0..side * side)
            .map(|i| origin + DVec3::new((i % side) as f64, (i / side) as f64, 0.0) * step)
            .collect()
    }

    fn shuffled(mut points: Vec<DVec3>, seed: u64) -> Vec<DVec3> {
        let mut rng = Rng::new(seed);
        for i in (1..points.len()).rev() {
            let j = rng.below(i as u64 + 1) as usize;
            points.swap(i, j);
        }
        points
    }

    fn estimate_in_chunks(points: &[DVec3], chunk: usize) -> Option<f64> {
        estimate_with(SpacingPatches::new(), points, chunk)
    }

    fn estimate_with(mut patches: SpacingPatches, points: &[DVec3], chunk: usize) -> Option<f64> {
        points.chunks(chunk).for_each(|c| patches.offer(c));
        patches.estimate()
    }

    #[test]
    fn a_shuffled_grid_has_its_step_as_spacing() {
        // Every point of a grid has its nearest neighbour one step away; the
        // first 65,536 of 360,000 shuffled points are a thin sample whose
        // own nearest distances average about 1.3 steps.
        for seed in [3u64, 11, 29] {
            let points = shuffled(grid(600, 0.25), seed);
            let first = crate::spatial::mean_nearest_distance(&points[..HEAD]).unwrap();
            assert!(first > 0.25 * 1.25, "the head alone: {first}");
            let estimate = estimate_in_chunks(&points, 50_000).unwrap();
            assert!((estimate - 0.25).abs() < 1e-9, "seed {seed}: {estimate}");
        }
    }

    #[test]
    fn a_grid_in_scan_order_has_its_step_as_spacing() {
        let estimate = estimate_in_chunks(&grid(600, 0.25), 7_777).unwrap();
        assert!((estimate - 0.25).abs() < 1e-9, "{estimate}");
    }

    #[test]
    fn a_shuffled_random_surface_matches_the_brute_force_mean() {
        // Points uniform on a unit sphere: the patches' mean nearest
        // distance is a sample of the whole cloud's, within a few per cent.
        for seed in [5u64, 17] {
            let mut rng = Rng::new(seed);
            let points: Vec<DVec3> = (0..200_000).map(|_| rng.unit_vector()).collect();
            let truth = crate::spatial::mean_nearest_distance(&points).unwrap();
            let estimate = estimate_in_chunks(&points, 65_000).unwrap();
            let error = (estimate / truth - 1.0).abs();
            assert!(error < 0.05, "seed {seed}: {estimate} against {truth}");
        }
    }

    #[test]
    fn short_streams_are_measured_whole() {
        let points = shuffled(grid(100, 2.0), 7);
        let whole = crate::spatial::mean_nearest_distance(&points);
        assert_eq!(estimate_in_chunks(&points, 333), whole);
        assert_eq!(estimate_in_chunks(&points[..1], 1), None);
        assert_eq!(estimate_in_chunks(&[DVec3::ONE; 100_000], 4096), None);
    }

    #[test]
    fn real_aerial_scans_shuffled_match_their_whole_mean() {
        // Two real aerial surveys (tests/fixtures/las), in file order and
        // shuffled as an octree-ordered or generated file would be, with
        // the head and patches scaled down to their size.
        for name in [
            "autzen_trim_cut.laz",
            "warsaw_small.las",
            "32-1-472-150-76.laz",
        ] {
            let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("tests/fixtures/las")
                .join(name);
            let mut reader =
                crate::io::open_reader(&path, crate::io::InvalidPolicy::Reject).unwrap();
            let points = crate::io::read_all_xyz(reader.as_mut()).unwrap();
            let truth = crate::spatial::mean_nearest_distance(&points).unwrap();
            let first = crate::spatial::mean_nearest_distance(&shuffled(points.clone(), 1)[..1024]);
            for (order, seed) in [("file", None), ("shuffled", Some(3)), ("shuffled", Some(8))] {
                let cloud = match seed {
                    Some(seed) => shuffled(points.clone(), seed),
                    None => points.clone(),
                };
                let estimate = estimate_with(SpacingPatches::with_sizes(1024, 512), &cloud, 4096);
                let error = (estimate.unwrap() / truth - 1.0).abs();
                assert!(
                    error < 0.1,
                    "{name} in {order} order: {estimate:?} against {truth} (the head alone: {first:?})"
                );
            }
        }
    }
}
