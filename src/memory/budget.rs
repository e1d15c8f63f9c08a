//! The memory budget: `--mem` (a promise about peak RSS) and the thread
//! count, turned into tile sizes.

/// Peak-RSS budget split between fixed costs and tiles in flight.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MemoryBudget {
    /// Peak resident memory the run promises to stay under, in bytes.
    pub bytes: u64,
    /// Worker threads (at least 1).
    pub threads: usize,
}

use super::plan::BASE_BYTES;

impl MemoryBudget {
    /// A budget of `bytes` for `threads` workers (0 threads counts as 1).
    pub fn new(bytes: u64, threads: usize) -> Self {
        MemoryBudget {
            bytes,
            threads: threads.max(1),
        }
    }

    /// Whether per-point state of `bytes_per_point` bytes for `points`
    /// points may stay in memory through a global pass: at most half of
    /// what is left beside the fixed costs. Beyond that, global passes take
    /// their external path, whose memory does not grow with the points.
    pub fn holds(&self, points: u64, bytes_per_point: u64) -> bool {
        points.saturating_mul(bytes_per_point) <= self.bytes.saturating_sub(BASE_BYTES) / 2
    }

    /// Largest tile (core points) such that `in_flight` tiles, each
    /// with `margin_factor` times its core points loaded at
    /// `bytes_per_point`, fit beside `reserved` bytes and the base cost.
    pub fn tile_points(
        &self,
        bytes_per_point: u64,
        margin_factor: f64,
        reserved: u64,
        in_flight: u64,
    ) -> u64 {
        let free = self.bytes.saturating_sub(BASE_BYTES + reserved);
        let per_tile = free / in_flight.max(1);
        let pts = per_tile as f64 / (bytes_per_point.max(1) as f64 * margin_factor.max(1.0));
        pts as u64
    }
}

/// This process's peak resident set size so far (Linux `VmHWM`), if known.
pub fn peak_rss_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tiles_shrink_with_budget_and_threads() {
        let a = MemoryBudget::new(1 << 30, 2).tile_points(400, 1.3, 0, 3);
        let b = MemoryBudget::new(256 << 20, 2).tile_points(400, 1.3, 0, 3);
        let c = MemoryBudget::new(256 << 20, 4).tile_points(400, 1.3, 0, 5);
        assert!(a > b && b > c, "{a} {b} {c}");
        assert!(b * 3 * 400 * 13 / 10 <= (256 << 20) - BASE_BYTES);
    }
}
