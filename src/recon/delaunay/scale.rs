//! The cloud's median nearest-neighbour distance, the same whatever the
//! tiling: the scale of the hole radius's ceiling ([`super::fan::SPARSEST`]).
//!
//! It is measured on a sample of points chosen by a hash of their input id
//! (every tiling samples the same points) in one pass over the tiles, each
//! sampled point's nearest distance found among its tile's loaded points
//! (`spatial::blocks`). A distance longer than the point's room in the
//! loaded region is known only to exceed that room; the median is exact
//! when it lies below every such room, and the pass is run again with a
//! wider margin when it does not. Exact duplicates are left out, as in the
//! mean spacing `sp` (a zero distance says nothing about the sampling).
//! The store's spacing estimate samples tiles, so it changes with the
//! tiling and may set only margins (ARCHITECTURE.md, "order and address").

use crate::pipeline::{run_tiles, KernelError, PipelineError, Progress, RunOptions, TileKernel};
use crate::spatial::blocks::Blocks;
use crate::store::sampling::LogHistogram;
use crate::store::PointStore;
use crate::tiling::TilePoints;
use rayon::prelude::*;

/// Points sampled, about: the median of 16k distances is within about 1 %
/// of the cloud's, which is finer than any use of it here.
const SAMPLE: u64 = 1 << 14;

/// Margin widenings tried before the sample's distances are taken as they
/// are (each quadruples the margin).
const WIDENINGS: usize = 4;

/// Whether the point of input id `id` is in the sample of one in `every`.
fn sampled(id: u64, every: u64) -> bool {
    // The high bits of a multiplicative (Fibonacci) hash, so a sample of a
    // structured input order (scan lines, a converter's chunks) is still
    // spread over the cloud; the low bits would keep `id % every` for a
    // power of two.
    (id.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 32).is_multiple_of(every)
}

/// One tile's share: the sampled distances known exactly, and of the rest,
/// how many there were and the smallest room any of them had.
struct Share {
    known: LogHistogram,
    unknown: u64,
    lowest_room: f64,
}

struct ScaleKernel {
    margin: f64,
    every: u64,
    scale: f64,
}

impl TileKernel for ScaleKernel {
    type Output = Share;

    fn name(&self) -> &'static str {
        "delaunay: median spacing"
    }

    fn margin(&self) -> f64 {
        self.margin
    }

    fn run(&self, tile: &TilePoints) -> Result<Share, KernelError> {
        let picked: Vec<usize> = (0..tile.n_core)
            .filter(|&i| sampled(tile.ids[i], self.every))
            .collect();
        let mut share = Share {
            known: LogHistogram::new(self.scale),
            unknown: 0,
            lowest_room: f64::INFINITY,
        };
        if picked.is_empty() {
            return Ok(share);
        }
        let blocks = Blocks::new(&tile.points);
        let found: Vec<(f64, f64)> = picked
            .par_iter()
            .map(|&i| {
                let d = blocks
                    .nearest_dist2(&tile.points, i)
                    .map_or(f64::INFINITY, f64::sqrt);
                (d, tile.room(tile.points[i]))
            })
            .collect();
        for (d, room) in found {
            if d <= room {
                if d > 0.0 {
                    share.known.add(d);
                }
            } else if room.is_finite() {
                share.unknown += 1;
                share.lowest_room = share.lowest_room.min(room);
            }
            // A point with no other point in an unbounded region has none
            // in the cloud: it has no spacing.
        }
        Ok(share)
    }
}

/// The median nearest-neighbour distance of the store's points (exact
/// duplicates left out), from a sample fixed by input ids; `estimate` (the
/// store's spacing estimate) sets the first margin and the histogram's
/// scale only. `None` when no sampled point has a neighbour.
pub fn median_spacing(
    store: &PointStore,
    estimate: f64,
    opts: RunOptions,
    progress: &dyn Progress,
) -> Result<Option<f64>, PipelineError> {
    // The bins must not depend on the tiling: the input's bounds and count
    // fix them, about a surface's spacing (the bins reach 24 octaves
    // either way).
    let extent = store.relative_bounds().extent().max_element();
    let mut kernel = ScaleKernel {
        margin: 4.0 * estimate,
        every: (store.len() / SAMPLE).max(1),
        scale: bin_scale(extent, store.len()),
    };
    let mut attempt = 0;
    loop {
        let mut known = LogHistogram::new(kernel.scale);
        let (mut unknown, mut lowest_room) = (0u64, f64::INFINITY);
        run_tiles(store, &kernel, opts, progress, |_, s| {
            known.merge(&s.known);
            unknown += s.unknown;
            lowest_room = lowest_room.min(s.lowest_room);
            Ok(())
        })?;
        let median = median_with_unknowns(&known, unknown);
        let exact = median.map_or(unknown == 0, |m| m < lowest_room);
        // Past the last widening (a margin of 4096 estimates) the sample's
        // distances are taken as found: only a cloud whose points are
        // mostly farther apart than that from the rest gets here.
        if exact || attempt == WIDENINGS {
            return Ok(median);
        }
        attempt += 1;
        kernel.margin *= 4.0;
    }
}

/// The histogram's scale for a cloud of `n` points spanning `extent`.
fn bin_scale(extent: f64, n: u64) -> f64 {
    if extent > 0.0 {
        extent / (n.max(1) as f64).sqrt()
    } else {
        1.0
    }
}

/// The median of the known distances and `unknown` more that exceed them
/// all, as the upper edge of its bin (`None` when the median is one of the
/// unknown ones). The edge, not the largest value below it: a tiling that
/// knows more of the larger distances must find the same median.
fn median_with_unknowns(known: &LogHistogram, unknown: u64) -> Option<f64> {
    let total = known.count() + unknown;
    let rank = total.div_ceil(2);
    (rank >= 1 && rank <= known.count())
        .then(|| known.ranked(rank))
        .flatten()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::progress::NoProgress;
    use crate::spatial::blocks::tests::cloud;
    use crate::store::{build_store, BuildOptions, TileTarget};

    /// The sample's median over the whole cloud at once: every sampled
    /// point's nearest distance among all points (`Blocks` is checked
    /// against brute force in its own tests).
    fn untiled(pts: &[glam::DVec3], scale: f64) -> Option<f64> {
        let every = (pts.len() as u64 / SAMPLE).max(1);
        let blocks = Blocks::new(pts);
        let mut h = LogHistogram::new(scale);
        for i in (0..pts.len()).filter(|&i| sampled(i as u64, every)) {
            if let Some(d2) = blocks.nearest_dist2(pts, i).filter(|&d2| d2 > 0.0) {
                h.add(d2.sqrt());
            }
        }
        h.ranked(h.count().div_ceil(2))
    }

    #[test]
    fn median_is_the_same_in_every_tiling() {
        // 40k points: one in two sampled; the cloud has exact duplicates
        // (left out) and far outliers (whose distances the tiles cannot
        // see, above the median).
        let pts = cloud(5, 40_000);
        for (k, per_tile) in [2_500u64, 9_000, 50_000].into_iter().enumerate() {
            let dir = tempfile::tempdir().unwrap();
            let mut reader = crate::io::memory::MemoryReader::new("cloud", pts.clone(), None);
            let opts = BuildOptions {
                tiles: TileTarget::Points(per_tile),
                ..Default::default()
            };
            let store =
                build_store(&mut reader, &dir.path().join("s"), &opts, &NoProgress).unwrap();
            // The stored (f32, relative) coordinates, in input order.
            let (mut stored, mut ids) = (Vec::new(), Vec::new());
            store.read_points(0, store.len(), &mut stored).unwrap();
            store.read_indices(0, store.len(), &mut ids).unwrap();
            let mut rel = vec![glam::DVec3::ZERO; stored.len()];
            ids.iter()
                .zip(&stored)
                .for_each(|(&id, &p)| rel[id as usize] = p);
            let extent = store.relative_bounds().extent().max_element();
            let estimate = crate::store::spacing::estimate_spacing(&store).unwrap();
            for threads in [1, 2] {
                let got = median_spacing(&store, estimate, RunOptions::new(threads), &NoProgress)
                    .unwrap()
                    .unwrap();
                let want = untiled(&rel, bin_scale(extent, store.len())).unwrap();
                assert_eq!(
                    got.to_bits(),
                    want.to_bits(),
                    "tiling {k}, {threads} threads"
                );
            }
        }
    }

    #[test]
    fn a_median_among_the_unknown_is_none() {
        let mut h = LogHistogram::new(1.0);
        [1.0, 2.0, 3.0].iter().for_each(|&v| h.add(v));
        assert_eq!(median_with_unknowns(&h, 0), h.ranked(2));
        assert_eq!(median_with_unknowns(&h, 3), h.ranked(3));
        assert!(h.ranked(2).unwrap() >= 2.0 && h.ranked(2).unwrap() < 2.03);
        assert_eq!(median_with_unknowns(&h, 4), None);
        assert_eq!(median_with_unknowns(&LogHistogram::new(1.0), 0), None);
    }
}
