//! The terminal side of [`scanmesh::pipeline::Progress`]: one indicatif bar
//! per stage with rate and ETA, on stderr, only when stderr is a terminal.

use indicatif::{ProgressBar, ProgressStyle};
use scanmesh::pipeline::{NoProgress, Progress};
use scanmesh::telemetry::Mark;
use std::io::IsTerminal;
use std::sync::Mutex;

/// Items a second, three significant digits with a k/M/G suffix
/// (indicatif's `{per_sec}` prints `7,841,517.0193/s`).
fn rate(state: &indicatif::ProgressState, w: &mut dyn std::fmt::Write) {
    let _ = write!(w, "{}/s", short_count(state.per_sec()));
}

/// `x` with three significant digits and a k/M/G suffix.
fn short_count(x: f64) -> String {
    let (v, unit) = match x.abs() {
        a if a >= 1e9 => (x / 1e9, "G"),
        a if a >= 1e6 => (x / 1e6, "M"),
        a if a >= 1e3 => (x / 1e3, "k"),
        _ => (x, ""),
    };
    let digits = if v.abs() >= 100.0 {
        0
    } else if v.abs() >= 10.0 {
        1
    } else {
        2
    };
    format!("{v:.digits$}{unit}")
}

pub struct Bars {
    bar: Mutex<Option<ProgressBar>>,
}

impl Progress for Bars {
    fn begin(&self, stage: &str, total: u64) {
        let bar = if total > 0 {
            ProgressBar::new(total).with_style(
                ProgressStyle::with_template(
                    "{prefix:>22} [{bar:30}] {human_pos}/{human_len} {rate} eta {eta}",
                )
                .unwrap_or_else(|_| ProgressStyle::default_bar())
                .with_key("rate", rate)
                .progress_chars("=> "),
            )
        } else {
            ProgressBar::new_spinner().with_style(
                ProgressStyle::with_template("{prefix:>22} {spinner} {human_pos} {rate}")
                    .unwrap_or_else(|_| ProgressStyle::default_spinner())
                    .with_key("rate", rate),
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

impl Timings {
    fn gap(&self) {
        if let Ok(mut last) = self.last_end.lock() {
            if last.elapsed().as_secs_f64() >= 0.005 {
                eprintln!("{:>24}: {}", "(between stages)", last.span());
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
                eprintln!("{stage:>24}: {}", t0.span());
                if let Ok(mut last) = self.last_end.lock() {
                    *last = Mark::now();
                }
            }
        }
    }
}

/// Stage timings on stderr when `SCANMESH_TIMINGS` is set (whatever
/// `--quiet` says: it is asked for by name).
pub fn timings() -> Option<Box<dyn Progress>> {
    std::env::var_os("SCANMESH_TIMINGS").map(|_| -> Box<dyn Progress> {
        Box::new(Timings {
            start: Mutex::new(None),
            last_end: Mutex::new(Mark::now()),
        })
    })
}

/// Bars when stderr is a terminal, nothing otherwise.
pub fn bars() -> Box<dyn Progress> {
    match std::io::stderr().is_terminal() {
        true => Box::new(Bars {
            bar: Mutex::new(None),
        }),
        false => Box::new(NoProgress),
    }
}

#[cfg(test)]
mod tests {
    use super::short_count;

    #[test]
    fn rates_read_short() {
        assert_eq!(short_count(7_841_517.019), "7.84M");
        assert_eq!(short_count(12_345.0), "12.3k");
        assert_eq!(short_count(999.0), "999");
        assert_eq!(short_count(0.5), "0.50");
        assert_eq!(short_count(2.5e9), "2.50G");
    }
}
