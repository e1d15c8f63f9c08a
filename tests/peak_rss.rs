//! `peak-rss` against a process of known size: a Python interpreter holding a
//! 200 MiB buffer, checked for the reported peak, the budget and exit codes.

use std::process::{Command, Output};

const MIB: u64 = 1 << 20;
const HOLD_200_MIB: &str = "x = bytearray(200 * 1024 * 1024); import time; time.sleep(0.2)";

fn peak_rss(args: &[&str]) -> Output {
    match Command::new(env!("CARGO_BIN_EXE_peak-rss"))
        .args(args)
        .output()
    {
        Ok(o) => o,
        Err(e) => panic!("cannot run peak-rss: {e}"),
    }
}

/// The report line (the last line of stderr).
fn report(out: &Output) -> String {
    let stderr = String::from_utf8_lossy(&out.stderr);
    stderr.lines().last().unwrap_or_default().to_string()
}

/// One `key=value` field of the report line.
fn field(out: &Output, key: &str) -> String {
    let line = report(out);
    line.split_whitespace()
        .find_map(|kv| kv.strip_prefix(&format!("{key}=")).map(str::to_string))
        .unwrap_or_else(|| panic!("no `{key}=` in report {line:?}"))
}

fn peak_of(out: &Output) -> u64 {
    field(out, "peak_rss_bytes")
        .parse()
        .expect("peak_rss_bytes is an integer")
}

fn json_report(out: &Output) -> serde_json::Value {
    let line = report(out);
    serde_json::from_str(&line).unwrap_or_else(|e| panic!("report is not JSON ({e}): {line}"))
}

#[test]
fn reports_a_200_mib_peak() {
    let out = peak_rss(&["--", "python3", "-c", HOLD_200_MIB]);
    assert!(out.status.success(), "{:?}: {}", out.status, report(&out));
    let peak = peak_of(&out);
    assert!(peak >= 200 * MIB, "peak {peak} < 200 MiB");
    // The interpreter itself is small: the peak must not be wildly inflated.
    assert!(peak < 400 * MIB, "peak {peak} implausibly large");
    assert_eq!(field(&out, "exit"), "0");
    let wall: f64 = field(&out, "wall_s").parse().expect("wall_s is a number");
    assert!(
        wall >= 0.2,
        "wall {wall} s shorter than the command's sleep"
    );
    assert!(field(&out, "peak_rss").ends_with("MiB"));
}

#[test]
fn budget_below_peak_fails_and_above_passes() {
    let over = peak_rss(&["--budget", "100MiB", "--", "python3", "-c", HOLD_200_MIB]);
    assert_eq!(over.status.code(), Some(3), "over budget must exit 3");
    assert_eq!(field(&over, "over_budget"), "true");
    assert_eq!(field(&over, "budget_bytes"), (100 * MIB).to_string());

    let under = peak_rss(&["--budget", "1GiB", "--", "python3", "-c", HOLD_200_MIB]);
    assert!(
        under.status.success(),
        "1 GiB budget must pass: {}",
        report(&under)
    );
    assert_eq!(field(&under, "over_budget"), "false");
}

#[test]
fn small_process_has_small_peak() {
    let out = peak_rss(&["--", "python3", "-c", "import time; time.sleep(0.1)"]);
    assert!(out.status.success(), "{}", report(&out));
    let peak = peak_of(&out);
    assert!(peak > 0 && peak < 100 * MIB, "peak {peak}");
}

#[test]
fn failing_command_propagates_its_code_in_json() {
    let script = "import time, sys; time.sleep(0.05); sys.exit(7)";
    let out = peak_rss(&["--json", "--", "python3", "-c", script]);
    assert_eq!(out.status.code(), Some(7));
    let json = json_report(&out);
    assert_eq!(json["exit"], 7);
    assert_eq!(json["over_budget"], false);
    assert!(json["peak_rss_bytes"].as_u64().is_some_and(|b| b > 0));
}

#[test]
fn killed_command_reports_the_signal() {
    let out = peak_rss(&["--json", "--", "sh", "-c", "sleep 0.05; kill -9 $$"]);
    assert_eq!(out.status.code(), Some(128 + 9));
    assert_eq!(json_report(&out)["signal"], 9);
}

#[test]
fn bad_budget_and_missing_command_are_errors() {
    let bad_unit = peak_rss(&["--budget", "12 furlongs", "--", "true"]);
    assert_eq!(bad_unit.status.code(), Some(2));
    assert_eq!(peak_rss(&["--json"]).status.code(), Some(2));
    let missing = peak_rss(&["--", "/nonexistent/command"]);
    assert_eq!(missing.status.code(), Some(1));
}

#[test]
fn report_can_go_to_a_file() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("report.txt");
    let path_str = path.to_string_lossy().to_string();
    let out = peak_rss(&["--output", &path_str, "--", "python3", "-c", "pass"]);
    assert!(out.status.success(), "{}", report(&out));
    let text = std::fs::read_to_string(&path).expect("report file");
    assert!(text.starts_with("peak_rss_bytes="), "{text}");
}
