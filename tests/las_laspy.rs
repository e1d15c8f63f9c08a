//! LAS kept whole, checked by laspy, a reader independent of scanmesh and
//! of the `las` crate (issue 38): laspy writes LAS 1.2 (point formats 0-3),
//! 1.3 (0-5) and 1.4 (0-10) with every field over its legal range (return
//! numbers 0-7 in formats 0-5, 0-15 and classes 0-255 in 6-10), extra
//! bytes, CRS VLRs and an EVLR (`tests/las_laspy.py gen`); scanmesh's
//! `convert` (.las, .laz) and `normals` (.las, .laz) outputs of those and
//! of the real fixtures are read back by laspy: every dimension, the
//! integer coordinates, scale, offset, version, format, VLRs and EVLRs
//! byte for byte (`las_laspy.py check`). Skipped, saying why, when python3
//! with laspy and lazrs is not there.

use std::path::{Path, PathBuf};
use std::process::Command;

fn script() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/las_laspy.py")
}

/// Whether python3 can import laspy and lazrs (LAZ); else why not.
fn laspy_missing() -> Option<String> {
    let out = Command::new("python3")
        .args(["-c", "import laspy, lazrs"])
        .output();
    match out {
        Err(e) => Some(format!("python3 not runnable: {e}")),
        Ok(o) if !o.status.success() => Some(format!(
            "python3 lacks laspy or lazrs: {}",
            String::from_utf8_lossy(&o.stderr).trim()
        )),
        Ok(_) => None,
    }
}

/// A scratch folder when laspy is there; else `None`, saying why the test
/// is skipped. `SCANMESH_REQUIRE_LASPY=1` (CI sets it once laspy is installed) makes
/// a missing laspy a failure rather than a skip.
fn laspy_or_skip() -> Option<tempfile::TempDir> {
    if let Some(why) = laspy_missing() {
        assert!(
            std::env::var("SCANMESH_REQUIRE_LASPY").is_err(),
            "SCANMESH_REQUIRE_LASPY is set but {why}"
        );
        eprintln!("skipping: {why}");
        return None;
    }
    Some(tempfile::tempdir().unwrap())
}

fn las_fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/las")
}

fn run(cmd: &mut Command, what: &str) -> String {
    let out = cmd.output().unwrap();
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(out.status.success(), "{what}: {text}");
    text
}

fn scanmesh(args: &[&str]) {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_scanmesh"));
    run(cmd.args(args).arg("-q"), &format!("scanmesh {args:?}"));
}

/// What an output gained over its input: "0" nothing, "1" normals and
/// flags, else the path of the curvature PLY whose values it gained.
type Gained = String;

/// Checks each (input, output, gained) with laspy, in one run.
fn check(pairs: &[(PathBuf, PathBuf, Gained)]) {
    use std::io::Write;
    let mut child = Command::new("python3")
        .arg(script())
        .arg("check")
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut lines = String::new();
    for (i, o, n) in pairs {
        lines += &format!("{}\t{}\t{n}\n", i.display(), o.display());
    }
    child
        .stdin
        .take()
        .unwrap()
        .write_all(lines.as_bytes())
        .unwrap();
    let out = child.wait_with_output().unwrap();
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "laspy check: {said}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(
        said.lines().filter(|l| l.starts_with("ok ")).count(),
        pairs.len(),
        "{said}"
    );
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// `convert` to .las and .laz and `normals` to .las and .laz of `input`;
/// the (input, output, gained) to check.
fn through_both_commands(input: &Path, dir: &Path) -> Vec<(PathBuf, PathBuf, Gained)> {
    let stem = input.file_stem().unwrap().to_string_lossy();
    let mut made = Vec::new();
    for ext in ["las", "laz"] {
        let conv = dir.join(format!("{stem}_c.{ext}"));
        scanmesh(&["convert", s(input), s(&conv)]);
        made.push((input.to_path_buf(), conv, "0".into()));
        let norm = dir.join(format!("{stem}_n.{ext}"));
        scanmesh(&["normals", s(input), "-o", s(&norm)]);
        made.push((input.to_path_buf(), norm, "1".into()));
    }
    made
}

#[test]
fn laspy_reads_every_field_back_for_every_version_and_format() {
    let Some(dir) = laspy_or_skip() else {
        return;
    };
    let mut cmd = Command::new("python3");
    run(cmd.arg(script()).arg("gen").arg(dir.path()), "laspy gen");
    let mut inputs: Vec<PathBuf> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    inputs.sort();
    assert_eq!(inputs.len(), 4 + 6 + 11, "{inputs:?}");
    let out = dir.path().join("out");
    std::fs::create_dir(&out).unwrap();
    let made: Vec<_> = inputs
        .iter()
        .flat_map(|i| through_both_commands(i, &out))
        .collect();
    check(&made);
}

#[test]
fn laspy_reads_every_field_of_the_real_files_back() {
    let Some(dir) = laspy_or_skip() else {
        return;
    };
    let fixtures = las_fixtures();
    let made = [
        "autzen.las",
        "32-1-472-150-76.laz",
        "pdal-test1_4.las",
        "autzen-trim-7-crop.las",
        "warsaw_small.las",
        "extrabytes.las",
    ]
    .map(|name| through_both_commands(&fixtures.join(name), dir.path()))
    .concat();
    check(&made);
}

/// `curvature` to .ply, .las, .laz and .pcd of `input`: the LAS outputs
/// to check against the input with laspy, the PCD checked here against
/// the PLY (both read by the script's own numpy readers).
fn curvature_everywhere(input: &Path, dir: &Path) -> Vec<(PathBuf, PathBuf, Gained)> {
    let stem = input.file_stem().unwrap().to_string_lossy();
    let out = |ext: &str| dir.join(format!("{stem}_k.{ext}"));
    let ply = out("ply");
    for ext in ["ply", "las", "laz", "pcd"] {
        scanmesh(&["curvature", s(input), "-o", s(&out(ext))]);
    }
    let mut cmd = Command::new("python3");
    cmd.arg(script()).args(["pcd", s(&out("pcd")), s(&ply)]);
    run(&mut cmd, &format!("PCD of {stem}"));
    let gained = ply.display().to_string();
    ["las", "laz"]
        .map(|ext| (input.to_path_buf(), out(ext), gained.clone()))
        .to_vec()
}

/// Curvature written through the output table: to LAS the input's own
/// records as they came with k1 k2 H K residual and the flags as described
/// extra bytes, to PCD as fields; every value bit for bit the PLY's, and
/// the curvature consistent (H the mean, K the product of k1 >= k2).
#[test]
fn laspy_reads_curvature_written_to_las_and_pcd() {
    let Some(dir) = laspy_or_skip() else {
        return;
    };
    let mut cmd = Command::new("python3");
    let generated = dir.path().join("gen");
    std::fs::create_dir(&generated).unwrap();
    run(cmd.arg(script()).arg("gen").arg(&generated), "laspy gen");
    let fixtures = las_fixtures();
    let inputs = [
        fixtures.join("autzen.las"),
        fixtures.join("32-1-472-150-76.laz"),
        fixtures.join("extrabytes.las"),
        generated.join("v12_f3.las"),
        generated.join("v14_f6.las"),
    ];
    let made: Vec<_> = inputs
        .iter()
        .flat_map(|i| curvature_everywhere(i, dir.path()))
        .collect();
    check(&made);
}

/// `outliers --drop` to LAS and LAZ: laspy finds the input's own records
/// where the full output has no outlier flag, in order, every dimension,
/// and the full output's scores.
#[test]
fn laspy_reads_the_records_outliers_drop_keeps() {
    let Some(dir) = laspy_or_skip() else {
        return;
    };
    let fixtures = las_fixtures();
    for name in [
        "autzen_trim_cut.laz",
        "32-1-472-150-76.laz",
        "warsaw_small.las",
    ] {
        let input = fixtures.join(name);
        let full = dir.path().join("all.las");
        scanmesh(&["outliers", s(&input), "-o", s(&full)]);
        for ext in ["las", "laz"] {
            let clean = dir.path().join(format!("clean.{ext}"));
            scanmesh(&["outliers", s(&input), "-o", s(&clean), "--drop"]);
            let mut cmd = Command::new("python3");
            cmd.arg(script())
                .args(["drop", s(&input), s(&full), s(&clean)]);
            run(&mut cmd, &format!("--drop of {name} to {ext}"));
        }
    }
}
