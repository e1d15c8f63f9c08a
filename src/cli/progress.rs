//! The terminal side of [`scanmesh::pipeline::Progress`]: one indicatif bar
//! per stage with rate and ETA, on stderr, only when stderr is a terminal.

use indicatif::{ProgressBar, ProgressStyle};
use scanmesh::pipeline::{NoProgress, Progress};
use std::io::IsTerminal;
use std::sync::Mutex;

pub struct Bars {
    bar: Mutex<Option<ProgressBar>>,
}

impl Progress for Bars {
    fn begin(&self, stage: &str, total: u64) {
        let bar = if total > 0 {
            ProgressBar::new(total).with_style(
                ProgressStyle::with_template(
                    "{prefix:>22} [{bar:30}] {human_pos}/{human_len} {per_sec} eta {eta}",
                )
                .unwrap_or_else(|_| ProgressStyle::default_bar())
                .progress_chars("=> "),
            )
        } else {
            ProgressBar::new_spinner().with_style(
                ProgressStyle::with_template("{prefix:>22} {spinner} {human_pos} {per_sec}")
                    .unwrap_or_else(|_| ProgressStyle::default_spinner()),
            )
        };
        bar.set_prefix(stage.to_string());
        if let Ok(mut slot) = self.bar.lock() {
            if let Some(old) = slot.replace(bar) {
                old.finish_and_clear();
            }
        }
    }

    fn advance(&self, n: u64) {
        if let Ok(slot) = self.bar.lock() {
            if let Some(bar) = slot.as_ref() {
                bar.inc(n);
            }
        }
    }

    fn end(&self) {
        if let Ok(mut slot) = self.bar.lock() {
            if let Some(bar) = slot.take() {
                bar.finish_and_clear();
            }
        }
    }
}

/// Stage timings on stderr (`SCANMESH_TIMINGS=1`), for profiling runs.
/// Time spent between stages (store setup, spacing, dropping and removing
/// scratch data) is printed as `(between stages)` so no cost hides. Each
/// line gives the wall time, the process CPU time (all threads; steadier
/// than wall time on a shared machine), the RSS at the end and the peak RSS
/// so far, to see which stage sets it, and the bytes read from and written
/// to storage.
struct Timings {
    start: Mutex<Option<(String, Mark)>>,
    last_end: Mutex<Mark>,
}

/// A point in wall time and process CPU time.
#[derive(Clone, Copy)]
struct Mark {
    wall: std::time::Instant,
    cpu: f64,
    io: [u64; 2],
}

impl Mark {
    fn now() -> Self {
        Mark {
            wall: std::time::Instant::now(),
            cpu: cpu_seconds().unwrap_or(0.0),
            io: io_bytes().unwrap_or([0; 2]),
        }
    }

    fn report(&self, name: &str) {
        let now = Mark::now();
        let io = |i: usize| scanmesh::units::human_bytes(now.io[i].saturating_sub(self.io[i]));
        eprintln!(
            "{:>24}: {:.3} s (cpu {:.2} s, rss {}, peak {}, disk r {} w {})",
            name,
            now.wall.duration_since(self.wall).as_secs_f64(),
            now.cpu - self.cpu,
            rss(),
            super::peak(),
            io(0),
            io(1)
        );
    }
}

/// User + system CPU time of the whole process (Linux; 10 ms ticks).
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

/// Bytes the process made the storage layer read and write (pages dirtied
/// through a mapping count too), from `/proc/self/io`.
fn io_bytes() -> Option<[u64; 2]> {
    let io = std::fs::read_to_string("/proc/self/io").ok()?;
    let field = |name: &str| {
        io.lines()
            .find_map(|l| l.strip_prefix(name)?.trim().parse::<u64>().ok())
    };
    Some([field("read_bytes:")?, field("write_bytes:")?])
}

fn rss() -> String {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    let kib = status
        .lines()
        .find(|l| l.starts_with("VmRSS:"))
        .and_then(|l| l.split_whitespace().nth(1)?.parse::<u64>().ok());
    kib.map_or("?".into(), |k| scanmesh::units::human_bytes(k * 1024))
}

impl Timings {
    fn gap(&self) {
        if let Ok(mut last) = self.last_end.lock() {
            if last.wall.elapsed().as_secs_f64() >= 0.005 {
                last.report("(between stages)");
            }
            *last = Mark::now();
        }
    }
}

impl Drop for Timings {
    fn drop(&mut self) {
        self.gap();
    }
}

impl Progress for Timings {
    fn begin(&self, stage: &str, _: u64) {
        self.gap();
        if let Ok(mut s) = self.start.lock() {
            *s = Some((stage.to_string(), Mark::now()));
        }
    }

    fn advance(&self, _: u64) {}

    fn end(&self) {
        if let Ok(mut s) = self.start.lock() {
            if let Some((stage, t0)) = s.take() {
                t0.report(&stage);
                if let Ok(mut last) = self.last_end.lock() {
                    *last = Mark::now();
                }
            }
        }
    }
}

/// Bars on a terminal, nothing otherwise or when `quiet`.
pub fn progress(quiet: bool) -> Box<dyn Progress> {
    if std::env::var_os("SCANMESH_TIMINGS").is_some() {
        return Box::new(Timings {
            start: Mutex::new(None),
            last_end: Mutex::new(Mark::now()),
        });
    }
    if quiet || !std::io::stderr().is_terminal() {
        Box::new(NoProgress)
    } else {
        Box::new(Bars {
            bar: Mutex::new(None),
        })
    }
}
