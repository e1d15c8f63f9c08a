//! What a stage cost the process: wall and CPU time, storage bytes, RSS,
//! read from `/proc/self` (Linux; elsewhere the fields read 0). This module
//! owns the measurement ([`Mark`], [`Span`]); what is done with it (a run's
//! report, `SCANMESH_TIMINGS` lines) belongs to its callers.

/// A point in wall time, process CPU time and storage traffic.
#[derive(Clone, Copy, Debug)]
pub struct Mark {
    wall: std::time::Instant,
    cpu: f64,
    io: [u64; 2],
}

/// The cost between two marks.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Span {
    /// Wall time, in seconds.
    pub wall_s: f64,
    /// User + system time of all threads (steadier than wall time on a
    /// shared machine).
    pub cpu_s: f64,
    /// Resident set size at the end.
    pub rss_bytes: u64,
    /// Peak RSS of the process so far (to see which stage sets it).
    pub peak_rss_bytes: u64,
    /// Bytes the process made the storage layer read.
    pub disk_read_bytes: u64,
    /// Bytes the process made the storage layer write (pages dirtied
    /// through a mapping count too).
    pub disk_written_bytes: u64,
}

impl Mark {
    /// This moment.
    pub fn now() -> Self {
        Mark {
            wall: std::time::Instant::now(),
            cpu: cpu_seconds().unwrap_or(0.0),
            io: io_bytes().unwrap_or([0; 2]),
        }
    }

    /// Wall time since this mark.
    pub fn elapsed(&self) -> std::time::Duration {
        self.wall.elapsed()
    }

    /// The cost from this mark to now.
    pub fn span(&self) -> Span {
        let now = Mark::now();
        Span {
            wall_s: now.wall.duration_since(self.wall).as_secs_f64(),
            cpu_s: now.cpu - self.cpu,
            rss_bytes: rss_bytes().unwrap_or(0),
            peak_rss_bytes: crate::memory::peak_rss_bytes().unwrap_or(0),
            disk_read_bytes: now.io[0].saturating_sub(self.io[0]),
            disk_written_bytes: now.io[1].saturating_sub(self.io[1]),
        }
    }
}

impl std::fmt::Display for Span {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let b = crate::units::human_bytes;
        write!(
            f,
            "{:.3} s (cpu {:.2} s, rss {}, peak {}, disk r {} w {})",
            self.wall_s,
            self.cpu_s,
            b(self.rss_bytes),
            b(self.peak_rss_bytes),
            b(self.disk_read_bytes),
            b(self.disk_written_bytes)
        )
    }
}

/// User + system CPU time of the whole process (10 ms ticks).
fn cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    let fields: Vec<&str> = stat
        .get(stat.rfind(')')? + 1..)?
        .split_whitespace()
        .collect();
    let ticks = |i: usize| fields.get(i)?.parse::<f64>().ok();
    // Fields 14 and 15 of stat(5), counted after the command name.
    Some((ticks(11)? + ticks(12)?) / 100.0)
}

/// Bytes the process made the storage layer read and write, from
/// `/proc/self/io`.
fn io_bytes() -> Option<[u64; 2]> {
    let io = std::fs::read_to_string("/proc/self/io").ok()?;
    let field = |name: &str| {
        io.lines()
            .find_map(|l| l.strip_prefix(name)?.trim().parse::<u64>().ok())
    };
    Some([field("read_bytes:")?, field("write_bytes:")?])
}

fn rss_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let kib = status
        .lines()
        .find(|l| l.starts_with("VmRSS:"))?
        .split_whitespace()
        .nth(1)?
        .parse::<u64>()
        .ok()?;
    Some(kib * 1024)
}
