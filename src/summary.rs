//! A run's closing line: a capability's report with what only the caller
//! knows (the seconds the run took, its peak memory, the output written).
//! Each capability renders its own report's line as `impl Display for
//! Summary<'_, ItsReport>`, so a caller of the library prints the same
//! line the command-line tool prints. The caller passes the three in, or
//! the moment its run began ([`Summary::since`]: the seconds and the peak
//! measured then).

use std::path::Path;
use std::time::Instant;

/// A report and the run it closes, displayed as the run's summary line.
#[derive(Clone, Copy, Debug)]
pub struct Summary<'a, R> {
    /// What the run computed.
    pub report: &'a R,
    /// Wall seconds the run took.
    pub secs: f64,
    /// The process's peak RSS in bytes, when the platform tells it.
    pub peak: Option<u64>,
    /// The output the run wrote.
    pub output: &'a Path,
}

impl<'a, R> Summary<'a, R> {
    /// The line of `report`, for a run of `secs` seconds peaking at
    /// `peak` bytes that wrote `output`.
    pub fn new(report: &'a R, secs: f64, peak: Option<u64>, output: &'a Path) -> Self {
        Summary {
            report,
            secs,
            peak,
            output,
        }
    }

    /// The line of `report`, for a run that began at `t0`, peaked at this
    /// process's peak so far and wrote `output`.
    pub fn since(report: &'a R, t0: Instant, output: &'a Path) -> Self {
        let peak = crate::memory::peak_rss_bytes();
        Summary::new(report, t0.elapsed().as_secs_f64(), peak, output)
    }

    /// The peak as the line prints it: `"?"` where the platform does not
    /// say.
    pub fn peak_text(&self) -> String {
        peak_text(self.peak)
    }
}

/// A peak RSS as summaries and logs print it (`"?"` when unknown).
pub fn peak_text(peak: Option<u64>) -> String {
    peak.map_or("?".into(), crate::units::human_bytes)
}
