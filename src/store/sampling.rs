//! Sampling statistics gathered by the normals kernel for later stages: the
//! nearest-neighbour distance (paper 1's rho, sampling density) and the
//! tangent-plane fit residual (its delta, noise), as mergeable log-scale
//! histograms so tiles can be summed in any grouping to the same result.
//! The store owns them because its manifest keeps them for later runs.

use serde::{Deserialize, Serialize};

/// Bins per octave, and octaves below and above the scale.
const PER_OCTAVE: f64 = 64.0;
const OCTAVES: i32 = 24;
const BINS: usize = (2 * OCTAVES) as usize * PER_OCTAVE as usize;
/// Fixed-point units per `scale` of the exact sum.
const SUM_UNIT: f64 = (1u64 << 40) as f64;
/// [`LogHistogram::slot`] of a zero (or negative, or NaN) value.
pub const ZERO_SLOT: u16 = 0;
/// [`LogHistogram::slot`] of a value beyond the bins.
pub const ABOVE_SLOT: u16 = BINS as u16 + 1;

/// Histogram of positive values on a log2 scale around `scale`, with 1.1 %
/// wide bins; zeros and values outside the range are counted apart.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LogHistogram {
    scale: f64,
    bins: Vec<u64>,
    zeros: u64,
    above: u64,
    max: f64,
    /// Sum of the positive values in units of `scale / 2^40`: an integer,
    /// so tiles merged in any grouping give the same mean to the last bit
    /// (a float sum would depend on the tiling).
    sum: u128,
}

impl LogHistogram {
    pub fn new(scale: f64) -> Self {
        LogHistogram {
            scale: if scale > 0.0 && scale.is_finite() {
                scale
            } else {
                1.0
            },
            bins: vec![0; BINS],
            zeros: 0,
            above: 0,
            max: 0.0,
            sum: 0,
        }
    }

    pub fn add(&mut self, v: f64) {
        let slot = self.slot(v);
        match slot {
            ZERO_SLOT => {
                self.zeros += 1;
                return;
            }
            ABOVE_SLOT => self.above += 1,
            s => self.bins[usize::from(s) - 1] += 1,
        }
        self.max = self.max.max(v);
        // Saturating: an absurd outlier must not wrap the sum.
        self.sum = self
            .sum
            .saturating_add((v / self.scale * SUM_UNIT).round().min(1e30) as u128);
    }

    /// Where [`Self::add`] counts `v`: [`ZERO_SLOT`] (zero, negative or
    /// NaN), `1 + bin`, or [`ABOVE_SLOT`] (beyond the bins). A value kept as
    /// its slot can be judged later against a cut that only the merged
    /// histogram knows ([`Self::outliers_from`]), exactly as the histogram
    /// counted it.
    pub fn slot(&self, v: f64) -> u16 {
        if v.is_nan() || v <= 0.0 {
            return ZERO_SLOT;
        }
        let b = ((v / self.scale).log2() + OCTAVES as f64) * PER_OCTAVE;
        if b < 0.0 {
            1
        } else if b >= BINS as f64 {
            ABOVE_SLOT
        } else {
            1 + b as u16
        }
    }

    pub fn merge(&mut self, o: &LogHistogram) {
        self.bins.iter_mut().zip(&o.bins).for_each(|(a, b)| *a += b);
        self.zeros += o.zeros;
        self.above += o.above;
        self.max = self.max.max(o.max);
        self.sum = self.sum.saturating_add(o.sum);
    }

    /// Mean of the positive values (0 when there are none), exact to the
    /// fixed-point unit.
    pub fn mean(&self) -> f64 {
        let positive = self.count() - self.zeros;
        if positive == 0 {
            return 0.0;
        }
        self.sum as f64 / SUM_UNIT * self.scale / positive as f64
    }

    pub fn count(&self) -> u64 {
        self.bins.iter().sum::<u64>() + self.zeros + self.above
    }

    fn upper_edge(&self, bin: usize) -> f64 {
        self.scale * ((bin + 1) as f64 / PER_OCTAVE - OCTAVES as f64).exp2()
    }

    /// The value below which a fraction `q` of the values lie (bin upper
    /// edge: at most 1.1 % high).
    pub fn quantile(&self, q: f64) -> f64 {
        let target = (q.clamp(0.0, 1.0) * self.count() as f64).ceil() as u64;
        self.ranked(target)
            .map_or(self.max, |edge| edge.min(self.max))
    }

    /// The upper edge of the bin holding the `target`-th smallest value,
    /// counting from 1 (0 for a zero): read off the bins alone, so two
    /// histograms whose bins agree up to it agree on it, whatever their
    /// larger values. `None` when it lies above the bins' range.
    pub fn ranked(&self, target: u64) -> Option<f64> {
        let mut seen = self.zeros;
        if seen >= target {
            return Some(0.0);
        }
        for (i, c) in self.bins.iter().enumerate() {
            seen += c;
            if seen >= target {
                return Some(self.upper_edge(i));
            }
        }
        None
    }

    /// Largest value not above `limit`, and how many values exceed it
    /// (those counted at [`Self::outliers_from`] or later).
    pub fn max_below(&self, limit: f64) -> (f64, u64) {
        let from = self.outliers_from(limit);
        let mut best = 0.0;
        let mut over = self.above;
        for (i, c) in self.bins.iter().enumerate() {
            if *c == 0 {
                continue;
            }
            if i + 1 < usize::from(from) {
                best = self.upper_edge(i).min(self.max);
            } else {
                over += c;
            }
        }
        (best, over)
    }

    /// The first slot ([`Self::slot`]) whose values lie beyond `limit`:
    /// the first bin whose upper edge (at most the largest value) exceeds
    /// it by more than a bin's width, else [`ABOVE_SLOT`]. Bins grow with
    /// their slot, so every later slot lies beyond too.
    pub fn outliers_from(&self, limit: f64) -> u16 {
        (0..BINS)
            .find(|&i| self.upper_edge(i).min(self.max) > limit * (1.0 + 1.0 / PER_OCTAVE))
            .map_or(ABOVE_SLOT, |i| 1 + i as u16)
    }
}

/// The surface-sampling facts later stages need, saved in the store manifest.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SamplingStats {
    /// Robust largest nearest-neighbour distance (paper 1's rho): the
    /// largest one not beyond 3x the 99th percentile.
    pub rho: f64,
    /// Points whose nearest neighbour lies beyond that (isolated outliers).
    pub rho_outliers: u64,
    /// Median nearest-neighbour distance.
    pub median_nn: f64,
    /// Mean nearest-neighbour distance, duplicates left out (the store's
    /// spacing estimate, but over every point: the same for any tiling).
    #[serde(default)]
    pub mean_nn: f64,
    /// Noise bound (paper 1's delta) estimated as twice the median RMS
    /// residual of the tangent-plane fits.
    pub noise: f64,
}

/// Per-tile accumulators of [`SamplingStats`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SamplingHistograms {
    pub nn: LogHistogram,
    pub residual: LogHistogram,
}

impl SamplingHistograms {
    pub fn new(spacing: f64) -> Self {
        SamplingHistograms {
            nn: LogHistogram::new(spacing),
            residual: LogHistogram::new(spacing),
        }
    }

    /// Whether these are histograms of at most `points` values, binned as
    /// [`Self::new`] bins them (a saved tile result's, checked before use).
    pub fn fits(&self, points: u64) -> bool {
        [&self.nn, &self.residual].iter().all(|h| {
            let counted = h
                .bins
                .iter()
                .try_fold(h.zeros.checked_add(h.above), |s, &b| {
                    s?.checked_add(b).map(Some)
                })
                .flatten();
            h.bins.len() == BINS
                && h.max.is_finite()
                && counted.is_some_and(|c| c <= points)
                && h.sum <= u128::from(points).saturating_mul(1e30 as u128)
        })
    }

    pub fn merge(&mut self, o: &SamplingHistograms) {
        self.nn.merge(&o.nn);
        self.residual.merge(&o.residual);
    }

    /// Beyond what nearest-neighbour distance a point is an isolated
    /// outlier: 3x the 99th percentile.
    pub fn isolation_limit(&self) -> f64 {
        3.0 * self.nn.quantile(0.99)
    }

    pub fn stats(&self) -> SamplingStats {
        let (rho, rho_outliers) = self.nn.max_below(self.isolation_limit());
        SamplingStats {
            rho,
            rho_outliers,
            median_nn: self.nn.quantile(0.5),
            mean_nn: self.nn.mean(),
            noise: 2.0 * self.residual.quantile(0.5),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantiles_within_a_bin() {
        let mut h = LogHistogram::new(1.0);
        for i in 1..=1000 {
            h.add(i as f64 / 100.0);
        }
        let q = h.quantile(0.5);
        assert!((q - 5.0).abs() / 5.0 < 0.012, "{q}");
        assert_eq!(h.quantile(1.0), 10.0);
    }

    #[test]
    fn outliers_do_not_set_rho() {
        let mut s = SamplingHistograms::new(1.0);
        for i in 0..10_000 {
            s.nn.add(1.0 + (i % 100) as f64 / 100.0);
            s.residual.add(0.1);
        }
        s.nn.add(50.0);
        s.nn.add(80.0);
        let st = s.stats();
        assert!(st.rho < 2.05 && st.rho > 1.95, "{st:?}");
        assert_eq!(st.rho_outliers, 2);
        assert!((st.noise - 0.2).abs() < 0.01);
    }

    #[test]
    fn slots_judge_points_as_the_histogram_counted_them() {
        let mut s = SamplingHistograms::new(1.0);
        let values: Vec<f64> = (0..10_000)
            .map(|i| 1.0 + (i % 100) as f64 / 100.0)
            .chain([0.0, 50.0, 80.0, 1e12])
            .collect();
        values.iter().for_each(|&v| s.nn.add(v));
        let from = s.nn.outliers_from(s.isolation_limit());
        let isolated: Vec<f64> = values
            .iter()
            .copied()
            .filter(|&v| s.nn.slot(v) >= from)
            .collect();
        assert_eq!(isolated, vec![50.0, 80.0, 1e12]);
        assert_eq!(s.stats().rho_outliers, 3);
        assert_eq!(s.nn.slot(0.0), ZERO_SLOT);
        assert_eq!(s.nn.slot(1e12), ABOVE_SLOT);
    }

    #[test]
    fn merge_is_order_free() {
        let mut a = LogHistogram::new(0.5);
        let mut b = LogHistogram::new(0.5);
        (1..100).for_each(|i| a.add(i as f64));
        (100..200).for_each(|i| b.add(i as f64));
        let mut ab = a.clone();
        ab.merge(&b);
        let mut ba = b.clone();
        ba.merge(&a);
        assert_eq!(ab, ba);
        assert!((ab.mean() - 100.0).abs() < 1e-9, "{}", ab.mean());
    }
}
