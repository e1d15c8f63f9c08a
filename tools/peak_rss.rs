//! `peak-rss`: run a command and report its peak resident set size, for the
//! memory-budget bench (`--mem` is a promise about peak RSS, mapped pages
//! included).
//!
//! ```text
//! peak-rss [--budget 256MiB] [--json] [--output FILE] -- <command> [args...]
//! ```
//!
//! The peak is the kernel's own high-water mark, `VmHWM` in
//! `/proc/<pid>/status` (resident anonymous + file-mapped + shared pages),
//! polled every `--interval-ms` (5 ms) while the child lives; each round
//! reads `VmHWM` first and then asks `Child::try_wait`, so the last value is
//! read right before the child is reaped. Limits, by construction:
//! - the kernel frees the address space at exit, before the zombie can be
//!   reaped, so growth during the final poll interval (< 5 ms) can be missed;
//!   a command that exits before the first poll is reported as unmeasured;
//! - only the direct child is measured, not its own children (use `exec` in
//!   wrapper scripts); threads share the process's memory and are included.
//!
//! The report goes to stderr (like `time`; the command owns stdout) or to
//! `--output`: `peak_rss_bytes=<n> peak_rss=<human> wall_s=<t> exit=<code>`
//! (plus `budget_bytes=` and `over_budget=` with `--budget`), or one JSON
//! object with `--json`.
//!
//! Exit status: the command's own status if it failed (128 + signal if it was
//! killed); otherwise 3 if the peak exceeded the budget or could not be
//! measured while a budget was set; 2 for usage errors; 1 if the command
//! could not be started; else 0.

use anyhow::Context;
use clap::Parser;
use scanmesh::units::{human_bytes, parse_size};
use std::ffi::OsString;
use std::path::PathBuf;
use std::process::{Command, ExitCode, ExitStatus};
use std::time::{Duration, Instant};

const EXIT_OVER_BUDGET: u8 = 3;

#[derive(Parser, Debug)]
#[command(
    name = "peak-rss",
    about = "Run a command and report its peak RSS (VmHWM)"
)]
struct Args {
    /// Fail (exit 3) if the peak exceeds this size: bytes or KiB/MiB/GiB/KB/MB/GB.
    #[arg(long, value_parser = parse_size)]
    budget: Option<u64>,
    /// Print the report as one JSON object.
    #[arg(long)]
    json: bool,
    /// Write the report to this file instead of stderr.
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Poll interval in milliseconds.
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u64).range(1..=1000))]
    interval_ms: u64,
    /// The command and its arguments (after `--`).
    #[arg(last = true, required = true, num_args = 1..)]
    command: Vec<OsString>,
}

/// What one run measured.
struct Report {
    peak: Option<u64>,
    wall: Duration,
    exit: i32,
    signal: Option<i32>,
    budget: Option<u64>,
}

impl Report {
    fn over_budget(&self) -> bool {
        match (self.budget, self.peak) {
            (Some(b), Some(p)) => p > b,
            (Some(_), None) => true,
            (None, _) => false,
        }
    }

    fn text(&self) -> String {
        let peak = self.peak.unwrap_or(0);
        let mut s = format!(
            "peak_rss_bytes={peak} peak_rss={} wall_s={:.3} exit={}",
            human_bytes(peak),
            self.wall.as_secs_f64(),
            self.exit
        );
        if self.peak.is_none() {
            s.push_str(" measured=false");
        }
        if let Some(b) = self.budget {
            s.push_str(&format!(
                " budget_bytes={b} over_budget={}",
                self.over_budget()
            ));
        }
        s
    }

    fn json(&self) -> String {
        serde_json::json!({
            "peak_rss_bytes": self.peak,
            "peak_rss": self.peak.map(human_bytes),
            "wall_s": self.wall.as_secs_f64(),
            "exit": self.exit,
            "signal": self.signal,
            "budget_bytes": self.budget,
            "over_budget": self.over_budget(),
        })
        .to_string()
    }
}

/// `VmHWM` of a `/proc/<pid>/status` text, in bytes (the kernel prints kB,
/// meaning KiB).
fn parse_vm_hwm(status: &str) -> Option<u64> {
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let mut fields = line["VmHWM:".len()..].split_whitespace();
    let value: u64 = fields.next()?.parse().ok()?;
    match fields.next() {
        Some("kB") => value.checked_mul(1024),
        _ => None,
    }
}

fn read_vm_hwm(pid: u32) -> Option<u64> {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?;
    parse_vm_hwm(&status)
}

/// Exit code and terminating signal of a finished child.
fn exit_of(status: ExitStatus) -> (i32, Option<i32>) {
    #[cfg(unix)]
    {
        use std::os::unix::process::ExitStatusExt;
        if let Some(sig) = status.signal() {
            return (128 + sig, Some(sig));
        }
    }
    (status.code().unwrap_or(1), None)
}

fn run(args: &Args) -> anyhow::Result<Report> {
    let (program, rest) = args
        .command
        .split_first()
        .context("no command given after `--`")?;
    let interval = Duration::from_millis(args.interval_ms);
    let start = Instant::now();
    let mut child = Command::new(program)
        .args(rest)
        .spawn()
        .with_context(|| format!("cannot start {}", program.to_string_lossy()))?;
    let pid = child.id();
    let mut peak: Option<u64> = None;
    let status = loop {
        // Read first, then reap: the last reading is as late as possible.
        if let Some(hwm) = read_vm_hwm(pid) {
            peak = Some(peak.map_or(hwm, |p| p.max(hwm)));
        }
        if let Some(status) = child.try_wait().context("waiting for the command")? {
            break status;
        }
        std::thread::sleep(interval);
    };
    let wall = start.elapsed();
    let (exit, signal) = exit_of(status);
    Ok(Report {
        peak,
        wall,
        exit,
        signal,
        budget: args.budget,
    })
}

fn emit(args: &Args, report: &Report) -> anyhow::Result<()> {
    let text = if args.json {
        report.json()
    } else {
        report.text()
    };
    match &args.output {
        Some(path) => std::fs::write(path, format!("{text}\n"))
            .with_context(|| format!("cannot write {}", path.display())),
        None => {
            eprintln!("{text}");
            Ok(())
        }
    }
}

fn main() -> ExitCode {
    let args = Args::parse();
    let report = match run(&args) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("peak-rss: {e:#}");
            return ExitCode::FAILURE;
        }
    };
    if let Err(e) = emit(&args, &report) {
        eprintln!("peak-rss: {e:#}");
        return ExitCode::FAILURE;
    }
    if report.exit != 0 {
        return ExitCode::from(u8::try_from(report.exit).unwrap_or(1).max(1));
    }
    if report.over_budget() {
        if report.peak.is_none() {
            eprintln!("peak-rss: the command exited before its RSS could be read");
        }
        return ExitCode::from(EXIT_OVER_BUDGET);
    }
    ExitCode::SUCCESS
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_vm_hwm() {
        let status =
            "Name:\tpython3\nVmPeak:\t  300000 kB\nVmHWM:\t  204812 kB\nVmRSS:\t 1000 kB\n";
        assert_eq!(parse_vm_hwm(status), Some(204812 * 1024));
        assert_eq!(parse_vm_hwm("Name:\tzombie\nState:\tZ (zombie)\n"), None);
        assert_eq!(parse_vm_hwm("VmHWM:\t 12 MB\n"), None);
    }

    #[test]
    fn reads_own_hwm() {
        let own = read_vm_hwm(std::process::id());
        assert!(own.is_some_and(|b| b > 1 << 20), "{own:?}");
    }
}
