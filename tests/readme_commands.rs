//! Every `scanmesh` command line of README.md's shell blocks runs verbatim
//! (through `sh`, comments and all) on small generated inputs and real
//! fixtures named as the README names them, in README order, in a temporary
//! folder: the README cannot drift from the binary.

use scanmesh::io::{create_writer, Format, PointChunk, WriterSpec};
use scanmesh::synth::{generate, mean_spacing_hint, Shape};
use std::path::{Path, PathBuf};
use std::process::Command;

/// The README's `scanmesh ...` lines, in order.
fn readme_commands() -> Vec<String> {
    let readme = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("README.md"))
        .expect("README.md");
    let mut inside = false;
    let mut lines = Vec::new();
    for line in readme.lines() {
        if line.starts_with("```") {
            inside = line == "```sh" && !inside;
            continue;
        }
        if inside && line.starts_with("scanmesh ") {
            lines.push(line.to_string());
        }
    }
    lines
}

fn fixture(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(rel)
}

/// A small binary PLY of `shape`, through the library's own writer.
fn write_ply(path: &Path, shape: &Shape, n: usize) {
    let sp = mean_spacing_hint(shape, n).expect("spacing");
    let scan = generate(shape, n, 0.1 * sp, 1).expect("scan");
    let mut w = create_writer(path, &WriterSpec::new(Format::PlyBinaryLe)).expect("writer");
    let chunk = PointChunk {
        xyz: scan.points,
        ..PointChunk::default()
    };
    w.write_chunk(&chunk, None).expect("write");
    w.finish().expect("finish");
}

fn run(dir: &Path, line: &str) -> std::process::Output {
    let exe = PathBuf::from(env!("CARGO_BIN_EXE_scanmesh"));
    let bin_dir = exe.parent().expect("bin dir");
    let path = format!(
        "{}:{}",
        bin_dir.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    Command::new("sh")
        .arg("-c")
        .arg(line)
        .current_dir(dir)
        .env("PATH", path)
        .env("SHARED", dir.join("shared"))
        .output()
        .expect("sh")
}

#[test]
fn every_readme_command_runs_as_written() {
    let commands = readme_commands();
    assert!(commands.len() >= 30, "{} commands found", commands.len());
    let dir = tempfile::tempdir().expect("tmp");
    let d = dir.path();
    std::fs::create_dir(d.join("shared")).expect("shared");
    write_ply(&d.join("scan.ply"), &Shape::torus(1.0, 0.3), 6_000);
    write_ply(&d.join("part.ply"), &Shape::unit_sphere(), 4_000);
    write_ply(&d.join("truth.ply"), &Shape::torus(1.0, 0.3), 6_000);
    write_ply(&d.join("dem.ply"), &Shape::wavy_sheet(), 4_000);
    for (from, to) in [
        ("las/autzen_trim_cut.laz", "scan.laz"),
        ("las/autzen_town_cut.las", "dem.las"),
        ("las/32-1-472-150-76.laz", "town.laz"),
        ("e57/three_scans.e57", "site.e57"),
    ] {
        std::fs::copy(fixture(from), d.join(to)).expect("fixture");
    }
    // `scan.las`: the README converts to it before reading it.
    let made = run(d, "scanmesh convert scan.ply scan.las -q");
    assert!(
        made.status.success(),
        "{}",
        String::from_utf8_lossy(&made.stderr)
    );
    for line in &commands {
        // A job by hand follows the script's earlier jobs, which the
        // README runs through `sh job.sh` (a line this test skips).
        if line.contains("run-job") {
            let before = run(
                d,
                "scanmesh run-job \"$SHARED/scan.run\" --until marching-cubes",
            );
            assert!(
                before.status.success(),
                "{}",
                String::from_utf8_lossy(&before.stderr)
            );
        }
        let o = run(d, line);
        assert!(
            o.status.success(),
            "README command failed: {line}\n{}",
            String::from_utf8_lossy(&o.stderr)
        );
    }
}
