//! Statistics of the neighbourhoods: a histogram of neighbourhood sizes and,
//! for topological neighbours, of the mean-reverse-shift iteration counts
//! (paper 3 step 6 reports c in 0..4 and |T| in [k, 3k]). Histograms are
//! integer counts, so merging tiles in any order gives the same numbers.

use serde::Serialize;

/// Size and iteration histograms over a set of points.
#[derive(Clone, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct HoodStats {
    /// `sizes[s]`: points with `s` neighbours.
    sizes: Vec<u64>,
    /// `iterations[c]`: points whose shift added points `c` times
    /// (topological only; empty for kNN).
    iterations: Vec<u64>,
    /// Points whose iteration was stopped by the cap.
    hit_cap: u64,
}

impl HoodStats {
    /// Counts one point with `size` neighbours and, for topological
    /// neighbours, its iteration count and whether the cap stopped it.
    pub fn add(&mut self, size: usize, iterations: Option<(u32, bool)>) {
        bump(&mut self.sizes, size);
        if let Some((c, hit_cap)) = iterations {
            bump(&mut self.iterations, c as usize);
            self.hit_cap += u64::from(hit_cap);
        }
    }

    /// Adds the counts of `other`.
    pub fn merge(&mut self, other: &HoodStats) {
        add_histogram(&mut self.sizes, &other.sizes);
        add_histogram(&mut self.iterations, &other.iterations);
        self.hit_cap += other.hit_cap;
    }

    /// Whether these are the counts of `points` points whose lists hold at
    /// most `longest` neighbours (a saved tile result's, checked before
    /// use: a histogram's length is a size it allocates when merged).
    pub(crate) fn fits(&self, points: u64, longest: usize) -> bool {
        let total = |h: &[u64]| h.iter().try_fold(0u64, |s, &c| s.checked_add(c));
        self.sizes.len() <= longest + 1
            && self.iterations.len() <= 1 << 16
            && total(&self.sizes) == Some(points)
            && total(&self.iterations).is_some_and(|n| n <= points)
            && self.hit_cap <= points
    }

    /// Points counted.
    pub fn points(&self) -> u64 {
        self.sizes.iter().sum()
    }

    /// Sum of all neighbourhood sizes.
    pub fn total(&self) -> u64 {
        self.sizes
            .iter()
            .enumerate()
            .map(|(s, &n)| s as u64 * n)
            .sum()
    }

    /// `[s]`: points with `s` neighbours.
    pub fn size_histogram(&self) -> &[u64] {
        &self.sizes
    }

    /// `[c]`: points whose reverse shift added points `c` times (empty for kNN).
    pub fn iteration_histogram(&self) -> &[u64] {
        &self.iterations
    }

    /// Points whose iteration the cap stopped.
    pub fn hit_cap(&self) -> u64 {
        self.hit_cap
    }

    /// Smallest neighbourhood size (`None` for no point).
    pub fn min_size(&self) -> Option<usize> {
        self.sizes.iter().position(|&n| n > 0)
    }

    /// Largest neighbourhood size (`None` for no point).
    pub fn max_size(&self) -> Option<usize> {
        self.sizes.iter().rposition(|&n| n > 0)
    }

    /// The size at rank `points / 2` in sorted order (the upper median).
    pub fn median_size(&self) -> Option<usize> {
        median(&self.sizes)
    }

    /// Mean neighbourhood size (`None` for no point).
    pub fn mean_size(&self) -> Option<f64> {
        let n = self.points();
        (n > 0).then(|| self.total() as f64 / n as f64)
    }

    /// Median iteration count (upper median), topological only.
    pub fn median_iterations(&self) -> Option<usize> {
        median(&self.iterations)
    }

    /// Fraction of points whose size lies in `[lo, hi]`.
    pub fn fraction_sized(&self, lo: usize, hi: usize) -> Option<f64> {
        let n = self.points();
        let inside: u64 = self
            .sizes
            .iter()
            .enumerate()
            .filter(|(s, _)| (lo..=hi).contains(s))
            .map(|(_, &c)| c)
            .sum();
        (n > 0).then(|| inside as f64 / n as f64)
    }
}

fn bump(h: &mut Vec<u64>, at: usize) {
    if h.len() <= at {
        h.resize(at + 1, 0);
    }
    h[at] += 1;
}

fn add_histogram(into: &mut Vec<u64>, from: &[u64]) {
    if into.len() < from.len() {
        into.resize(from.len(), 0);
    }
    into.iter_mut().zip(from).for_each(|(a, b)| *a += b);
}

fn median(h: &[u64]) -> Option<usize> {
    let n: u64 = h.iter().sum();
    if n == 0 {
        return None;
    }
    let rank = n / 2;
    let mut seen = 0;
    h.iter().position(|&c| {
        seen += c;
        seen > rank
    })
}

/// Sizes in the summary file.
#[derive(Clone, Debug, Serialize)]
pub struct SizeSummary {
    pub min: usize,
    pub median: usize,
    pub mean: f64,
    pub max: usize,
    /// Fraction of points with `k <= |N| <= 3k` (paper 3's typical range).
    pub within_k_3k: f64,
}

/// Iterations in the summary file (topological only).
#[derive(Clone, Debug, Serialize)]
pub struct IterationSummary {
    pub max_iterations: usize,
    /// `histogram[c]`: points whose reverse shift added points `c` times.
    pub histogram: Vec<u64>,
    pub median: usize,
    /// Points stopped by `max_iterations` while queries still added points.
    pub hit_cap: u64,
}

/// The `--summary` JSON document.
#[derive(Clone, Debug, Serialize)]
pub struct Summary {
    /// `topological` or `knn`.
    pub mode: &'static str,
    /// The `k` asked for.
    pub k: usize,
    /// Points given a list.
    pub points: u64,
    /// Tiles processed.
    pub tiles: usize,
    /// Tiles rerun with a wider margin.
    pub tiles_reloaded: usize,
    /// Widest margin a tile was finally run with, in the store's coordinate units.
    pub largest_margin: f64,
    /// Total neighbour entries written.
    pub neighbours: u64,
    /// Neighbourhood sizes (absent for no point).
    pub size: Option<SizeSummary>,
    /// Iteration counts (topological only).
    pub iterations: Option<IterationSummary>,
    /// Wall-clock seconds of the run.
    pub seconds: f64,
}

impl SizeSummary {
    pub fn of(stats: &HoodStats, k: usize) -> Option<Self> {
        Some(SizeSummary {
            min: stats.min_size()?,
            median: stats.median_size()?,
            mean: stats.mean_size()?,
            max: stats.max_size()?,
            within_k_3k: stats.fraction_sized(k, 3 * k)?,
        })
    }
}

impl IterationSummary {
    pub fn of(stats: &HoodStats, max_iterations: usize) -> Option<Self> {
        Some(IterationSummary {
            max_iterations,
            histogram: stats.iteration_histogram().to_vec(),
            median: stats.median_iterations()?,
            hit_cap: stats.hit_cap(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn histogram_statistics_match_a_sorted_list() {
        let sizes = [15usize, 17, 15, 30, 22, 15, 16, 45, 18];
        let mut a = HoodStats::default();
        let mut b = HoodStats::default();
        for (i, &s) in sizes.iter().enumerate() {
            let target = if i % 2 == 0 { &mut a } else { &mut b };
            target.add(s, Some((i as u32 % 3, i == 4)));
        }
        a.merge(&b);
        let mut sorted = sizes.to_vec();
        sorted.sort_unstable();
        assert_eq!(a.points(), 9);
        assert_eq!(a.min_size(), Some(15));
        assert_eq!(a.max_size(), Some(45));
        assert_eq!(a.median_size(), Some(sorted[sorted.len() / 2]));
        let sum: usize = sizes.iter().sum();
        assert_eq!(a.total(), sum as u64);
        assert_eq!(a.mean_size(), Some(sum as f64 / 9.0));
        assert_eq!(a.iteration_histogram(), &[3, 3, 3]);
        assert_eq!(a.median_iterations(), Some(1));
        assert_eq!(a.hit_cap(), 1);
        assert_eq!(a.fraction_sized(15, 30), Some(8.0 / 9.0));
    }

    #[test]
    fn empty_statistics_have_no_median() {
        let s = HoodStats::default();
        assert_eq!(s.median_size(), None);
        assert_eq!(s.mean_size(), None);
        assert!(SizeSummary::of(&s, 15).is_none());
    }
}
