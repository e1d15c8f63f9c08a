//! The command line on bad input and bad output: a clear error naming the
//! file, a non-zero exit, no panic, and no output file that looks complete.

use std::path::Path;
use std::process::Output;

mod common;
use common::scanmesh;

fn assert_fails_naming(out: &Output, name: &str) {
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "succeeded: {err}");
    assert!(err.contains(name), "error does not name {name}: {err}");
    assert!(!err.contains("panicked"), "panic: {err}");
}

fn write(dir: &Path, name: &str, body: &[u8]) -> String {
    let p = dir.join(name);
    std::fs::write(&p, body).expect("write fixture");
    p.display().to_string()
}

fn no_output_left(dir: &Path, name: &str) {
    let left: Vec<_> = std::fs::read_dir(dir)
        .expect("list")
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains(name))
        .collect();
    assert!(left.is_empty(), "left behind: {left:?}");
}

const GOOD_XYZ: &[u8] = b"0 0 0\n1 0 0\n0 1 0\n1 1 0\n0.5 0.5 0.1\n0.2 0.7 0\n0.9 0.1 0\n0.3 0.3 0\n0.6 0.8 0\n0.1 0.9 0\n0.8 0.6 0\n0.4 0.1 0\n0.7 0.4 0\n0.2 0.2 0\n0.9 0.9 0\n";

#[test]
fn missing_input_is_an_error() {
    let dir = tempfile::tempdir().expect("tmp");
    let out = dir.path().join("n.ply");
    let o = scanmesh(&[
        "normals",
        "/nonexistent/scan.ply",
        "-o",
        out.to_str().unwrap_or(""),
    ]);
    assert_fails_naming(&o, "/nonexistent/scan.ply");
    no_output_left(dir.path(), "n.ply");
}

#[test]
fn truncated_ply_is_an_error_and_leaves_no_output() {
    let dir = tempfile::tempdir().expect("tmp");
    let mut body = b"ply\nformat binary_little_endian 1.0\nelement vertex 1000\nproperty float x\nproperty float y\nproperty float z\nend_header\n".to_vec();
    body.extend(std::iter::repeat_n(0u8, 12 * 10));
    let input = write(dir.path(), "cut.ply", &body);
    let out = dir.path().join("cut_normals.ply");
    let o = scanmesh(&[
        "normals",
        &input,
        "-o",
        out.to_str().unwrap_or(""),
        "--quiet",
    ]);
    assert_fails_naming(&o, "cut.ply");
    no_output_left(dir.path(), "cut_normals");
}

#[test]
fn nan_coordinates_are_rejected_or_skipped_with_a_count() {
    let dir = tempfile::tempdir().expect("tmp");
    let mut body = GOOD_XYZ.to_vec();
    body.extend_from_slice(b"nan 0 0\n");
    let input = write(dir.path(), "nan.xyz", &body);
    let out = dir.path().join("nan_n.ply");
    let o = scanmesh(&[
        "normals",
        &input,
        "-o",
        out.to_str().unwrap_or(""),
        "--quiet",
        "--k",
        "6",
    ]);
    assert_fails_naming(&o, "nan.xyz");
    let o = scanmesh(&[
        "convert",
        &input,
        out.to_str().unwrap_or(""),
        "--skip-invalid",
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stdout).contains("15 points (1 skipped)"));
}

#[test]
fn garbage_and_empty_inputs_are_errors() {
    let dir = tempfile::tempdir().expect("tmp");
    let garbage = write(
        dir.path(),
        "garbage.ply",
        b"ply\nformat nonsense\n\x00\x01\x02",
    );
    let empty = write(dir.path(), "empty.xyz", b"");
    for input in [&garbage, &empty] {
        let o = scanmesh(&["info", input, "--quiet"]);
        assert_fails_naming(
            &o,
            Path::new(input)
                .file_name()
                .and_then(|n| n.to_str())
                .unwrap_or(""),
        );
    }
}

#[test]
fn absurd_header_count_fails_fast() {
    let dir = tempfile::tempdir().expect("tmp");
    let input = write(
        dir.path(),
        "huge.ply",
        b"ply\nformat binary_little_endian 1.0\nelement vertex 999999999999999\nproperty float x\nproperty float y\nproperty float z\nend_header\n\0\0\0\0",
    );
    let o = scanmesh(&[
        "convert",
        &input,
        dir.path().join("o.xyz").to_str().unwrap_or(""),
        "--quiet",
    ]);
    assert_fails_naming(&o, "huge.ply");
}

#[test]
fn unwritable_output_is_an_error() {
    let dir = tempfile::tempdir().expect("tmp");
    let input = write(dir.path(), "ok.xyz", GOOD_XYZ);
    let o = scanmesh(&["convert", &input, "/nonexistent/dir/out.ply", "--quiet"]);
    assert_fails_naming(&o, "/nonexistent/dir/out.ply");
}

#[test]
fn bad_options_are_errors() {
    let dir = tempfile::tempdir().expect("tmp");
    let input = write(dir.path(), "ok.xyz", GOOD_XYZ);
    let out = dir.path().join("o.ply");
    let out = out.to_str().unwrap_or("");
    for bad in [
        ["--mem", "12 parsecs"],
        ["--threads", "0"],
        ["--k", "1"],
        ["--viewpoint", "1,2"],
    ] {
        let o = scanmesh(&["normals", &input, "-o", out, bad[0], bad[1]]);
        assert!(!o.status.success(), "{bad:?} accepted");
    }
    for share in ["--min-piece=1.5", "--min-piece=-0.1", "--min-piece=NaN"] {
        let o = scanmesh(&["reconstruct", &input, "-o", out, share]);
        assert_fails_naming(&o, "--min-piece");
        assert!(!dir.path().join("o.ply").exists());
    }
}

#[test]
fn degenerate_flat_cloud_gets_normals() {
    let dir = tempfile::tempdir().expect("tmp");
    let input = write(dir.path(), "flat.xyz", GOOD_XYZ);
    let out = dir.path().join("flat_n.xyz");
    let o = scanmesh(&[
        "normals",
        &input,
        "-o",
        out.to_str().unwrap_or(""),
        "--quiet",
        "--k",
        "5",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(&out).expect("output");
    assert_eq!(text.lines().count(), 15);
}

#[test]
fn a_budget_below_every_plan_fails_fast_naming_the_minimum() {
    let dir = tempfile::tempdir().expect("tmp");
    let input = write(dir.path(), "ok.xyz", GOOD_XYZ);
    let out = dir.path().join("o.ply");
    for cmd in ["normals", "reconstruct", "neighbors", "tile"] {
        let o = scanmesh(&[
            cmd,
            &input,
            "-o",
            out.to_str().unwrap_or(""),
            "--mem",
            "1KiB",
        ]);
        assert_fails_naming(&o, "--mem 1.00KiB is too small");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains("needs at least"), "{cmd}: {err}");
        no_output_left(dir.path(), "o.ply");
    }
}

#[test]
fn a_missing_output_directory_is_named_and_not_created() {
    let dir = tempfile::tempdir().expect("tmp");
    let input = write(dir.path(), "ok.xyz", GOOD_XYZ);
    let missing = dir.path().join("typo/out.ply");
    for cmd in ["normals", "reconstruct", "neighbors"] {
        let o = scanmesh(&[cmd, &input, "-o", missing.to_str().unwrap_or(""), "--quiet"]);
        assert_fails_naming(&o, "typo");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains("output directory"), "{cmd}: {err}");
        assert!(
            !dir.path().join("typo").exists(),
            "{cmd} created the directory"
        );
    }
}

#[test]
fn a_store_in_use_is_refused_not_corrupted() {
    let dir = tempfile::tempdir().expect("tmp");
    let input = write(dir.path(), "ok.xyz", GOOD_XYZ);
    let store = dir.path().join("s");
    let o = scanmesh(&[
        "tile",
        &input,
        "-o",
        store.to_str().unwrap_or(""),
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // Hold the store as a run would, then start a second run on it.
    let held = scanmesh::store::PointStore::open(&store).expect("open");
    let out = dir.path().join("n.ply");
    let o = scanmesh(&[
        "normals",
        store.to_str().unwrap_or(""),
        "-o",
        out.to_str().unwrap_or(""),
        "--quiet",
        "--k",
        "5",
    ]);
    assert_fails_naming(&o, "in use by another scanmesh process");
    assert!(!out.exists());
    drop(held);
    let o = scanmesh(&[
        "normals",
        store.to_str().unwrap_or(""),
        "-o",
        out.to_str().unwrap_or(""),
        "--quiet",
        "--k",
        "5",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

#[test]
fn report_records_stages_and_outcome() {
    let dir = tempfile::tempdir().expect("tmp");
    let input = write(dir.path(), "in.xyz", GOOD_XYZ);
    let out = dir.path().join("n.ply").display().to_string();
    let report = dir.path().join("run.json");
    let r = report.to_str().unwrap_or("");
    let o = scanmesh(&[
        "normals", &input, "-o", &out, "-q", "--k", "6", "--report", r,
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&report).expect("report")).expect("json");
    assert_eq!(json["outcome"], "ok");
    assert!(json["summary"]
        .as_str()
        .unwrap_or("")
        .starts_with("normals: 15 points"));
    let stages: Vec<&str> = json["stages"]
        .as_array()
        .expect("stages")
        .iter()
        .filter_map(|s| s["name"].as_str())
        .collect();
    for want in ["read", "scatter", "normals", "write"] {
        assert!(stages.contains(&want), "no {want} in {stages:?}");
    }
    assert!(json["total"]["peak_rss_bytes"].as_u64().unwrap_or(0) > 0);
    // A failed run is reported as such, and still fails.
    let o = scanmesh(&[
        "normals",
        "/nonexistent/scan.ply",
        "-o",
        &out,
        "--report",
        r,
    ]);
    assert_fails_naming(&o, "/nonexistent/scan.ply");
    let text = std::fs::read_to_string(&report).expect("report");
    assert!(
        text.contains("\"outcome\": \"error: reading /nonexistent/scan.ply"),
        "{text}"
    );
    no_output_left(dir.path(), ".run.json.partial");
}

#[test]
fn a_store_whose_manifest_disagrees_with_its_columns_is_refused() {
    let dir = tempfile::tempdir().expect("tmp");
    let input = write(dir.path(), "in.xyz", GOOD_XYZ);
    let store = dir.path().join("s");
    let s = store.to_str().unwrap_or("");
    assert!(scanmesh(&["tile", &input, "-o", s, "-q"]).status.success());
    let manifest = store.join("manifest.json");
    let text = std::fs::read_to_string(&manifest).expect("manifest");
    // The manifest's checksum refuses any edit before its counts are read
    // (the counts are checked against the columns too: the fuzz target).
    for (from, to, says) in [
        // The store's count and its one tile's, both.
        ("\"count\": 15", "\"count\": 16", "manifest.json: damaged"),
        (
            "\"count\": 15",
            "\"count\": 18446744073709551615",
            "manifest.json: damaged",
        ),
    ] {
        std::fs::write(&manifest, text.replace(from, to)).expect("edit");
        let out = dir.path().join("n.ply").display().to_string();
        let o = scanmesh(&["normals", s, "-o", &out, "--k", "6"]);
        assert_fails_naming(&o, says);
        no_output_left(dir.path(), "n.ply");
    }
}

#[test]
fn delaunay_on_one_repeated_point_fails_naming_the_input() {
    let dir = tempfile::tempdir().expect("tempdir");
    let input = write(dir.path(), "same.xyz", "1 2 3\n".repeat(1000).as_bytes());
    let out = dir.path().join("m.ply");
    let run = scanmesh(&[
        "reconstruct",
        &input,
        "-o",
        out.to_str().unwrap(),
        "--method",
        "delaunay",
        "-q",
    ]);
    assert_fails_naming(&run, "same.xyz");
    assert!(String::from_utf8_lossy(&run.stderr).contains("all one point"));
    assert!(!out.exists());
}

#[test]
fn threads_and_memory_beyond_the_machine_are_refused() {
    let dir = tempfile::tempdir().expect("tmp");
    let input = write(dir.path(), "ok.xyz", GOOD_XYZ);
    let out = dir.path().join("o.ply");
    let run = dir.path().join("run");
    for (flag, value, says) in [
        ("--threads", "100000", "8 x the"),
        ("--mem", "100TiB", "more than this machine can give (RAM"),
    ] {
        let started = std::time::Instant::now();
        let o = scanmesh(&[
            "normals",
            &input,
            "-o",
            out.to_str().unwrap_or(""),
            "--run-dir",
            run.to_str().unwrap_or(""),
            flag,
            value,
            "-q",
        ]);
        assert_fails_naming(&o, &format!("{flag} "));
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains(says), "{flag} {value}: {err}");
        assert!(
            started.elapsed().as_secs() < 30,
            "{flag} {value}: refused late"
        );
        assert!(!out.exists());
        // Refused before the run directory is made: the corrected command
        // line then starts afresh, not against a recorded one.
        assert!(!run.exists(), "{flag} {value}: a run directory was made");
    }
}

/// GOOD_XYZ with one record that has no finite coordinates.
fn nan_xyz() -> Vec<u8> {
    let mut body = GOOD_XYZ.to_vec();
    body.extend_from_slice(b"nan 0 0\n");
    body
}

fn stdout(o: &Output) -> String {
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    String::from_utf8_lossy(&o.stdout).into_owned()
}

const SKIP_NOTE: &str = "1 record skipped (non-finite coordinates";

#[test]
fn skipped_records_are_counted_in_every_summary_and_the_report() {
    let dir = tempfile::tempdir().expect("tmp");
    let input = write(dir.path(), "nan.xyz", &nan_xyz());
    let report = dir.path().join("run.json");
    let r = report.to_str().unwrap_or("");
    let out = dir.path().join("n.ply").display().to_string();
    let o = scanmesh(&[
        "normals",
        &input,
        "-o",
        &out,
        "-q",
        "--k",
        "6",
        "--skip-invalid",
        "--report",
        r,
    ]);
    let said = stdout(&o);
    assert!(said.starts_with("normals: 15 points"), "{said}");
    assert!(
        said.contains(SKIP_NOTE) && said.contains("nan.xyz"),
        "{said}"
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&report).expect("report")).expect("json");
    assert_eq!(json["skipped_invalid"], 1, "{json}");
    assert!(json["summary"].as_str().unwrap_or("").contains(SKIP_NOTE));
    // convert, tile, and a command run on the store tile built.
    let xyz = dir.path().join("o.xyz").display().to_string();
    let said = stdout(&scanmesh(&[
        "convert",
        &input,
        &xyz,
        "--skip-invalid",
        "-q",
    ]));
    assert!(said.contains(SKIP_NOTE), "convert: {said}");
    let store = dir.path().join("s").display().to_string();
    let said = stdout(&scanmesh(&[
        "tile",
        &input,
        "-o",
        &store,
        "--skip-invalid",
        "-q",
    ]));
    assert!(said.contains(SKIP_NOTE), "tile: {said}");
    let said = stdout(&scanmesh(&[
        "normals", &store, "-o", &out, "-q", "--k", "6",
    ]));
    assert!(said.contains(SKIP_NOTE), "normals on the store: {said}");
    // A last line cut short is dropped and counted the same way.
    let cut = write(dir.path(), "cut.xyz", &[GOOD_XYZ, b"7 8 9.2"].concat());
    let said = stdout(&scanmesh(&["convert", &cut, &xyz, "--skip-invalid", "-q"]));
    assert!(
        said.contains("15 points") && said.contains("1 record skipped"),
        "{said}"
    );
    // Nothing skipped: nothing said, and the report counts 0.
    let good = write(dir.path(), "good.xyz", GOOD_XYZ);
    let o = scanmesh(&[
        "normals", &good, "-o", &out, "-q", "--k", "6", "--report", r,
    ]);
    assert!(!stdout(&o).contains("skipped"));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&report).expect("report")).expect("json");
    assert_eq!(json["skipped_invalid"], 0, "{json}");
}

#[test]
fn info_accepts_skip_invalid_and_counts_what_it_would_skip() {
    let dir = tempfile::tempdir().expect("tmp");
    let input = write(dir.path(), "nan.xyz", &nan_xyz());
    // The error names the flag, and the flag is accepted.
    let o = scanmesh(&["info", &input, "-q"]);
    assert_fails_naming(&o, "--skip-invalid");
    let o = scanmesh(&["info", &input, "-q", "--json", "--skip-invalid"]);
    let json: serde_json::Value = serde_json::from_str(&stdout(&o)).expect("json");
    assert_eq!(
        (json["points"].as_u64(), json["skipped_invalid"].as_u64()),
        (Some(15), Some(1))
    );
    let o = scanmesh(&["info", &input, "-q", "--plan", "--skip-invalid"]);
    assert!(stdout(&o).contains("plan for 15 points"));
    // Every command with a disk plan prints it.
    for command in [
        "normals",
        "reconstruct",
        "neighbors",
        "curvature",
        "features",
    ] {
        let args = [
            "info",
            &input,
            "-q",
            "--plan",
            "--skip-invalid",
            "--command",
            command,
        ];
        let text = stdout(&scanmesh(&args));
        assert!(
            text.contains("disk at the peak: the store"),
            "{command}: {text}"
        );
    }
}

/// `info` reads as text (no Debug names, no quotes), and an error that
/// quotes its cause does not repeat it as "caused by".
#[test]
fn info_is_plain_text_and_errors_say_each_cause_once() {
    let dir = tempfile::tempdir().expect("tmp");
    let input = write(dir.path(), "a.xyz", b"0 0 0\n1 0 0\n0 1 0\n1 1 0.5\n");
    let o = scanmesh(&["info", &input, "-q"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("format: XYZ text"), "{text}");
    assert!(text.contains("bounds max: [1, 1, 0.5]"), "{text}");
    assert!(!text.contains('"'), "{text}");
    let missing = dir.path().join("missing.ply");
    let o = scanmesh(&["info", missing.to_str().expect("utf8"), "-q"]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("missing.ply"), "{err}");
    assert_eq!(err.matches("No such file").count(), 1, "{err}");
}

/// Commands that keep no run directory neither list nor take its options
/// (they listed `--run-dir`, `--restart`, `--emit` and `--tasks` and then
/// refused them); the commands that keep one list them all.
#[test]
fn only_commands_that_keep_a_run_list_its_options() {
    let run_options = ["--run-dir", "--restart", "--emit", "--tasks"];
    for args in [
        &["convert", "in.ply", "out.ply"][..],
        &["tile", "in.ply", "-o", "out"],
        &["demo"],
    ] {
        let command = args[0];
        let help = scanmesh(&[command, "--help"]);
        let text = String::from_utf8_lossy(&help.stdout);
        for option in run_options {
            assert!(!text.contains(option), "{command} --help lists {option}");
        }
        let o = scanmesh(&[args, &["--run-dir", "d"]].concat());
        assert_fails_naming(&o, "unexpected argument '--run-dir'");
        assert!(!Path::new("d").exists());
    }
    for command in [
        "normals",
        "curvature",
        "outliers",
        "features",
        "neighbors",
        "reconstruct",
    ] {
        let help = scanmesh(&[command, "--help"]);
        let text = String::from_utf8_lossy(&help.stdout);
        for option in run_options {
            assert!(text.contains(option), "{command} --help lacks {option}");
        }
    }
}

/// `convert --unselected keep` to a format without a named flags field
/// (XYZ text, E57) is refused: the unselected rows could not be told
/// from the selected ones (an XYZ file got a nameless fourth column).
#[test]
fn keeping_unselected_points_needs_a_flags_field() {
    let dir = tempfile::tempdir().expect("tmp");
    let input = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/las/autzen.las");
    let select = ["--classes", "2", "--unselected", "keep", "-q"];
    for name in ["o.xyz", "o.e57"] {
        let out = dir.path().join(name);
        let args = [
            &["convert", input.to_str().unwrap(), out.to_str().unwrap()][..],
            &select,
        ]
        .concat();
        let o = scanmesh(&args);
        assert_fails_naming(&o, "no named flags field");
        no_output_left(dir.path(), name);
    }
    let out = dir.path().join("o.ply");
    let args = [
        &["convert", input.to_str().unwrap(), out.to_str().unwrap()][..],
        &select,
    ]
    .concat();
    assert!(scanmesh(&args).status.success());
}
