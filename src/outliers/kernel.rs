//! The tile kernel of the outlier scores: each core point's mean distance
//! to its `k` nearest neighbours, taken only when their ball lies inside
//! the loaded region (else the tile asks for a wider margin), so a score
//! is the same whatever the tiling.

use super::FEWER_THAN_K;
use crate::pipeline::{KernelError, TileKernel, TilePoints};
use crate::spatial::{build_index, KnnBackend};
use crate::stats::ExactSum;

/// The outliers' tile kernel: scores per core point.
pub struct ScoreKernel {
    pub(super) k: usize,
    /// First margin to load; the pipeline widens it when a tile asks.
    pub(super) margin: f64,
    /// The unit of the order-free sums.
    pub(super) scale: f64,
    pub(super) bytes_per_point: u64,
}

/// One tile's scores and flags in store order, and their sums.
pub struct TileScores {
    pub(super) scores: Vec<f32>,
    pub(super) flags: Vec<u8>,
    pub(super) sums: Sums,
}

/// Order-free sums of the scores and their squares (for the mean and the
/// standard deviation of the rule), over the points with k neighbours.
#[derive(Clone, Copy, Debug)]
pub(super) struct Sums {
    pub(super) score: ExactSum,
    pub(super) square: ExactSum,
}

impl Sums {
    pub(super) fn new(scale: f64) -> Self {
        Sums {
            score: ExactSum::new(scale),
            square: ExactSum::new(scale * scale),
        }
    }

    pub(super) fn merge(&mut self, o: &Sums) {
        self.score.merge(&o.score);
        self.square.merge(&o.square);
    }
}

impl TileKernel for ScoreKernel {
    type Output = TileScores;

    fn name(&self) -> &'static str {
        super::OUTLIER_SCORES.name()
    }

    fn margin(&self) -> f64 {
        self.margin
    }

    fn bytes_per_loaded_point(&self) -> Option<u64> {
        Some(self.bytes_per_point)
    }

    fn run(&self, tile: &TilePoints) -> Result<TileScores, KernelError> {
        let index =
            build_index(KnnBackend::Grid, &tile.points, &tile.ids).map_err(KernelError::failed)?;
        let (mut found, mut short) = (Vec::new(), 0.0f64);
        let mut out = TileScores {
            scores: Vec::with_capacity(tile.n_core),
            flags: Vec::with_capacity(tile.n_core),
            sums: Sums::new(self.scale),
        };
        for (i, &p) in tile.core_points().iter().enumerate() {
            index.knn(p, self.k, Some(i as u32), &mut found);
            // Fewer than k loaded: how far the k-th lies is unknown (the
            // whole cloud loaded has no shortfall, and then it has fewer).
            let reach = match found.get(self.k - 1) {
                Some(n) => n.dist2.sqrt(),
                None => f64::INFINITY,
            };
            short = short.max(tile.shortfall(p, reach));
            let sum: f64 = found.iter().map(|n| n.dist2.sqrt()).sum();
            let score = match found.len() {
                0 => f32::NAN,
                n => (sum / n as f64) as f32,
            };
            let flag = match found.len() < self.k {
                true => FEWER_THAN_K,
                false => {
                    out.sums.score.add(f64::from(score));
                    out.sums.square.add(f64::from(score) * f64::from(score));
                    0
                }
            };
            out.scores.push(score);
            out.flags.push(flag);
        }
        // The library's one margin rule: reload wider, or accept.
        KernelError::unless_short(short, tile.margin)?;
        Ok(out)
    }
}
