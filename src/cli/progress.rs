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
/// scratch data) is printed as `(between stages)` so no cost hides; each
/// stage line ends with the peak RSS so far, to see which stage sets it.
struct Timings {
    start: Mutex<Option<(String, std::time::Instant)>>,
    last_end: Mutex<std::time::Instant>,
}

impl Timings {
    fn gap(&self, now: std::time::Instant) {
        if let Ok(mut last) = self.last_end.lock() {
            let gap = now.duration_since(*last).as_secs_f64();
            if gap >= 0.005 {
                eprintln!("{:>24}: {:.3} s", "(between stages)", gap);
            }
            *last = now;
        }
    }
}

impl Drop for Timings {
    fn drop(&mut self) {
        self.gap(std::time::Instant::now());
    }
}

impl Progress for Timings {
    fn begin(&self, stage: &str, _: u64) {
        let now = std::time::Instant::now();
        self.gap(now);
        if let Ok(mut s) = self.start.lock() {
            *s = Some((stage.to_string(), now));
        }
    }

    fn advance(&self, _: u64) {}

    fn end(&self) {
        if let Ok(mut s) = self.start.lock() {
            if let Some((stage, t0)) = s.take() {
                eprintln!(
                    "{:>24}: {:.3} s (peak {})",
                    stage,
                    t0.elapsed().as_secs_f64(),
                    super::peak()
                );
                if let Ok(mut last) = self.last_end.lock() {
                    *last = std::time::Instant::now();
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
            last_end: Mutex::new(std::time::Instant::now()),
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
