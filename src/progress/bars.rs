//! The terminal side of [`Progress`]: one indicatif bar per stage with rate
//! and ETA, on stderr, only when stderr is a terminal (`SCANMESH_TIMINGS`'
//! lines are the run log's `StageLines`).

use super::{NoProgress, Progress};
use crate::units::short_count;
use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::sync::Mutex;

/// Items a second, three significant digits with a k/M/G suffix
/// (indicatif's `{per_sec}` prints `7,841,517.0193/s`).
fn rate(state: &indicatif::ProgressState, w: &mut dyn std::fmt::Write) {
    let _ = write!(w, "{}/s", short_count(state.per_sec()));
}

/// One bar at a time, the current stage's.
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

/// Bars when stderr is a terminal, nothing otherwise.
pub fn bars() -> Box<dyn Progress> {
    match std::io::stderr().is_terminal() {
        true => Box::new(Bars {
            bar: Mutex::new(None),
        }),
        false => Box::new(NoProgress),
    }
}
