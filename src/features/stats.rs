//! Order-free statistics of the curvature pass, summed over tiles in any
//! grouping to the same bits: fixed-point sums (`crate::stats`; a float sum
//! would depend on the tiling) and the project's log histograms for
//! quantiles.

pub(crate) use crate::stats::ExactSum;
use crate::store::sampling::LogHistogram;

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
