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

use std::path::Path;

/// Bytes that are not tiles: binary, thread stacks, allocator slack, I/O
/// buffers (the read chunk, the merge buffers of the edge runs).
pub const BASE_BYTES: u64 = 48 << 20;

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

/// A run whose peak RSS went over its memory promise: its outputs are
/// whole, but its plan failed (the plan, not the data, was wrong).
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[error("the run's peak memory {} went over --mem {}: its outputs are complete, but its memory plan failed (please report it with the command line)", crate::units::human_bytes(*peak), crate::units::human_bytes(*promise))]
pub struct PeakOver {
    /// The process's peak RSS, in bytes.
    pub peak: u64,
    /// The promise, in bytes.
    pub promise: u64,
}

/// Checks this process's peak RSS so far against the promise of `promise`
/// bytes (kept when the platform does not tell the peak), so a budget
/// bench or a cluster's memory limit learns a broken promise from the
/// exit code.
pub fn within_promise(promise: u64) -> Result<(), PeakOver> {
    match peak_rss_bytes() {
        Some(peak) if peak > promise => Err(PeakOver { peak, promise }),
        _ => Ok(()),
    }
}

/// This process's peak resident set size so far (Linux `VmHWM`), if known.
pub fn peak_rss_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// What memory this process can have: the machine's RAM and its control
/// group's limit, each when known (Linux; elsewhere both are `None`). A
/// `--mem` beyond the smaller is a promise the machine cannot keep: the
/// plan would size tiles for memory that is not there, and the run would
/// swap or be killed by the out-of-memory killer hours in.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MachineMemory {
    /// Total RAM (`MemTotal` in `/proc/meminfo`), in bytes.
    pub ram: Option<u64>,
    /// The smallest memory limit of this process's control group and its
    /// ancestors (cgroup v2 `memory.max`, v1 `memory.limit_in_bytes`), in
    /// bytes; `None` when there is none. A cluster's job gets one.
    pub cgroup: Option<u64>,
}

impl MachineMemory {
    /// The RAM and control group limit of this process, read from `/proc`
    /// and `/sys/fs/cgroup`.
    pub fn of_this_process() -> Self {
        MachineMemory {
            ram: std::fs::read_to_string("/proc/meminfo")
                .ok()
                .and_then(|t| mem_total(&t)),
            cgroup: std::fs::read_to_string("/proc/self/cgroup")
                .ok()
                .and_then(|t| cgroup_limit(&t, Path::new("/sys/fs/cgroup"))),
        }
    }

    /// The most this process can hold: the smaller of the two, if either
    /// is known.
    pub fn limit(&self) -> Option<u64> {
        match (self.ram, self.cgroup) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }
}

/// `MemTotal` of a `/proc/meminfo` text, in bytes.
fn mem_total(meminfo: &str) -> Option<u64> {
    let line = meminfo.lines().find(|l| l.starts_with("MemTotal:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    kib.checked_mul(1024)
}

/// The smallest memory limit on the way from the control group that
/// `proc_cgroup` (a `/proc/self/cgroup` text) names up to the root of the
/// hierarchy mounted under `root`. A directory that is not there (a
/// container sees its own group as the root) is passed over.
fn cgroup_limit(proc_cgroup: &str, root: &Path) -> Option<u64> {
    let mut limits = Vec::new();
    for line in proc_cgroup.lines() {
        let mut fields = line.splitn(3, ':');
        let (Some(id), Some(controllers), Some(path)) =
            (fields.next(), fields.next(), fields.next())
        else {
            continue;
        };
        let (mount, file) = if id == "0" && controllers.is_empty() {
            (root.to_path_buf(), "memory.max")
        } else if controllers.split(',').any(|c| c == "memory") {
            (root.join("memory"), "memory.limit_in_bytes")
        } else {
            continue;
        };
        let leaf = mount.join(path.trim_start_matches('/'));
        for dir in leaf.ancestors().take_while(|d| d.starts_with(&mount)) {
            let value = std::fs::read_to_string(dir.join(file)).ok();
            limits.extend(value.as_deref().and_then(limit_value));
        }
    }
    limits.into_iter().min()
}

/// A control group limit file's value in bytes; `None` for no limit
/// (v2 writes `max`, v1 a number near 2^63 rounded down to a page).
fn limit_value(text: &str) -> Option<u64> {
    let bytes: u64 = text.trim().parse().ok()?;
    (bytes < 1 << 62).then_some(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A peak over the promise fails the run, naming both; under it, it
    /// passes.
    #[test]
    fn a_peak_over_the_promise_fails_the_run() {
        let over = within_promise(1024).expect_err("this process holds more than 1 KiB");
        let said = over.to_string();
        assert!(said.contains("went over --mem 1.00KiB"), "{said}");
        assert!(within_promise(u64::MAX).is_ok());
    }

    #[test]
    fn tiles_shrink_with_budget_and_threads() {
        let a = MemoryBudget::new(1 << 30, 2).tile_points(400, 1.3, 0, 3);
        let b = MemoryBudget::new(256 << 20, 2).tile_points(400, 1.3, 0, 3);
        let c = MemoryBudget::new(256 << 20, 4).tile_points(400, 1.3, 0, 5);
        assert!(a > b && b > c, "{a} {b} {c}");
        assert!(b * 3 * 400 * 13 / 10 <= (256 << 20) - BASE_BYTES);
    }

    #[test]
    fn machine_memory_from_proc_and_cgroup_files() {
        let meminfo = "MemTotal:       24576000 kB\nMemFree:  1 kB\n";
        assert_eq!(mem_total(meminfo), Some(24_576_000 * 1024));
        assert_eq!(limit_value("max\n"), None);
        assert_eq!(limit_value("9223372036854771712\n"), None);
        assert_eq!(limit_value("8589934592\n"), Some(8 << 30));

        let root = tempfile::tempdir().expect("tmp");
        let r = root.path();
        // v2: the job's group (4 GiB) below a user slice (6 GiB).
        std::fs::create_dir_all(r.join("user.slice/job")).expect("mkdir");
        std::fs::write(r.join("user.slice/memory.max"), "6442450944\n").expect("w");
        std::fs::write(r.join("user.slice/job/memory.max"), "4294967296\n").expect("w");
        assert_eq!(cgroup_limit("0::/user.slice/job\n", r), Some(4 << 30));
        // v1: the memory controller's own hierarchy; "unlimited" is none.
        std::fs::create_dir_all(r.join("memory/slurm/uid_0/job_7")).expect("mkdir");
        std::fs::write(
            r.join("memory/memory.limit_in_bytes"),
            "9223372036854771712",
        )
        .expect("w");
        std::fs::write(
            r.join("memory/slurm/uid_0/job_7/memory.limit_in_bytes"),
            "1073741824",
        )
        .expect("w");
        let v1 = "12:cpu,cpuacct:/slurm\n4:memory:/slurm/uid_0/job_7\n0::/\n";
        assert_eq!(cgroup_limit(v1, r), Some(1 << 30));
        // A group the container does not see: its own root answers.
        assert_eq!(cgroup_limit("4:memory:/elsewhere/x\n", r), None);
        let m = MachineMemory {
            ram: Some(16 << 30),
            cgroup: Some(4 << 30),
        };
        assert_eq!(m.limit(), Some(4 << 30));
        assert_eq!(MachineMemory { cgroup: None, ..m }.limit(), Some(16 << 30));
    }
}
