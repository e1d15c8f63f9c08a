//! Order-free statistics of the curvature pass, summed over tiles in any
//! grouping to the same bits: fixed-point sums (a float sum would depend on
//! the tiling) and the project's log histograms for quantiles.

use crate::store::sampling::LogHistogram;

/// Fixed-point units per `scale`.
const UNIT: f64 = (1u64 << 40) as f64;

/// A sum of non-negative values in units of `scale / 2^40`, and their count.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExactSum {
    scale: f64,
    sum: u128,
    count: u64,
}

impl ExactSum {
    pub fn new(scale: f64) -> Self {
        ExactSum {
            scale: if scale > 0.0 && scale.is_finite() {
                scale
            } else {
                1.0
            },
            sum: 0,
            count: 0,
        }
    }

    /// Adds `v` (NaN and negative values count as zero).
    pub fn add(&mut self, v: f64) {
        let units = (v / self.scale * UNIT).round();
        // Saturating: an absurd value must not wrap the sum.
        self.sum += if units > 0.0 {
            units.min(1e30) as u128
        } else {
            0
        };
        self.count += 1;
    }

    pub fn merge(&mut self, o: &ExactSum) {
        self.sum += o.sum;
        self.count += o.count;
    }

    /// Mean of the values (0 for none).
    pub fn mean(&self) -> f64 {
        if self.count == 0 {
            return 0.0;
        }
        self.sum as f64 / UNIT * self.scale / self.count as f64
    }
}

/// What the curvature pass measured, for reports and for the feature
/// thresholds' defaults.
#[derive(Clone, Debug, PartialEq)]
pub struct CurvatureStats {
    /// `|k_i|`, the principal curvature of larger magnitude, of every point
    /// with an oriented curvature.
    pub dominant: LogHistogram,
    /// Squared RMS residual of each fit (mean: the cloud's RMS squared).
    pub residual2: ExactSum,
    /// RMS residual of each fit (for its median: the noise level of the
    /// smooth parts, which creases do not inflate as they do the RMS).
    pub residual: LogHistogram,
    /// Largest `|E_j|` of any fit.
    pub max_error: f64,
    /// Points per flag bit (sparse, degenerate, ill-conditioned, unoriented).
    pub flagged: [u64; 4],
}

impl CurvatureStats {
    /// Scales: `spacing` for lengths, `1 / spacing` for curvatures.
    pub fn new(spacing: f64) -> Self {
        CurvatureStats {
            dominant: LogHistogram::new(1.0 / spacing),
            residual2: ExactSum::new(spacing * spacing),
            residual: LogHistogram::new(spacing),
            max_error: 0.0,
            flagged: [0; 4],
        }
    }

    pub fn merge(&mut self, o: &CurvatureStats) {
        self.dominant.merge(&o.dominant);
        self.residual2.merge(&o.residual2);
        self.residual.merge(&o.residual);
        self.max_error = self.max_error.max(o.max_error);
        for (a, b) in self.flagged.iter_mut().zip(o.flagged) {
            *a += b;
        }
    }

    /// Counts the flag bits of one point.
    pub fn count_flags(&mut self, flags: u8) {
        for (bit, n) in self.flagged.iter_mut().enumerate() {
            if flags & (1 << bit) != 0 {
                *n += 1;
            }
        }
    }

    /// RMS of the fits' residuals over the points that have a fit.
    pub fn rms(&self) -> f64 {
        self.residual2.mean().sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_sum_is_grouping_free() {
        let vals: Vec<f64> = (0..1000)
            .map(|i| (i as f64 * 0.37).sin().abs() * 1e-4)
            .collect();
        let mut all = ExactSum::new(1e-4);
        vals.iter().for_each(|v| all.add(*v));
        let mut parts = ExactSum::new(1e-4);
        for chunk in vals.chunks(37).rev() {
            let mut p = ExactSum::new(1e-4);
            chunk.iter().for_each(|v| p.add(*v));
            parts.merge(&p);
        }
        assert_eq!(all, parts);
        let want = vals.iter().sum::<f64>() / vals.len() as f64;
        assert!(
            (all.mean() - want).abs() < 1e-12 * want.max(1e-12),
            "{}",
            all.mean()
        );
    }
}
