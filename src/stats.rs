//! Order-free statistics: sums that give the same bits whatever the tiling
//! and the grouping of the parts, so thresholds computed from them (the
//! curvature's noise, the outlier rule) do not change with `--tile-points`
//! or `--threads`. A float sum depends on its order; a fixed-point one
//! does not.

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
    /// An empty sum in units of `scale / 2^40` (a non-positive or
    /// infinite scale counts as 1).
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

    /// Adds another sum of the same scale.
    pub fn merge(&mut self, o: &ExactSum) {
        self.sum += o.sum;
        self.count += o.count;
    }

    /// Values added.
    pub fn count(&self) -> u64 {
        self.count
    }

    /// Mean of the values (0 for none).
    pub fn mean(&self) -> f64 {
        if self.count == 0 {
            return 0.0;
        }
        self.sum as f64 / UNIT * self.scale / self.count as f64
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
