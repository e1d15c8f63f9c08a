//! Resumable runs (`--run-dir`), tile jobs (`run-job`) and job scripts
//! (`--emit`): whatever order the parts run in, whatever was lost on the
//! way (tiles, a damaged tile file, the output), the result is byte for
//! byte the one a plain run writes; a changed input or command line is
//! refused.

use glam::DVec3;
use scanmesh::synth::fibonacci::fibonacci_sphere;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn scanmesh(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_scanmesh"))
        .args(args)
        .output()
        .expect("run scanmesh")
}

fn ok(args: &[&str]) -> String {
    let o = scanmesh(args);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "scanmesh {args:?} failed: {err}");
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn fails_saying(args: &[&str], words: &str) {
    let o = scanmesh(args);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "scanmesh {args:?} succeeded");
    assert!(err.contains(words), "error does not say `{words}`: {err}");
    assert!(!err.contains("panicked"), "panic: {err}");
}

struct Case {
    _dir: tempfile::TempDir,
    root: PathBuf,
    input: String,
}

impl Case {
    /// A 20,000-point sphere with a bump (so the tiles differ), as XYZ.
    fn new() -> Case {
        let dir = tempfile::tempdir().expect("tmp");
        let root = dir.path().to_path_buf();
        let pts = fibonacci_sphere(DVec3::ZERO, 1.0, 20_000);
        let text: String = pts
            .iter()
            .map(|p| {
                let p = *p * (1.0 + 0.2 * (-(*p - DVec3::Z).length_squared() * 4.0).exp());
                format!("{} {} {}\n", p.x, p.y, p.z)
            })
            .collect();
        let input = root.join("sphere.xyz");
        std::fs::write(&input, text).expect("write input");
        Case {
            _dir: dir,
            input: input.display().to_string(),
            root,
        }
    }

    fn path(&self, name: &str) -> String {
        self.root.join(name).display().to_string()
    }

    /// `reconstruct` of the case with extra arguments, writing `out`.
    fn reconstruct(&self, out: &str, extra: &[&str]) -> Vec<String> {
        let mut args = vec![
            "reconstruct".to_string(),
            self.input.clone(),
            "-o".into(),
            self.path(out),
            "--closed".into(),
            "--tile-points".into(),
            "2500".into(),
            "-q".into(),
        ];
        args.extend(extra.iter().map(|s| s.to_string()));
        args
    }
}

fn strs(v: &[String]) -> Vec<&str> {
    v.iter().map(String::as_str).collect()
}

fn same_file(a: &str, b: &str) {
    let (x, y) = (
        std::fs::read(a).expect("read"),
        std::fs::read(b).expect("read"),
    );
    assert!(!x.is_empty());
    assert!(x == y, "{a} and {b} differ");
}

fn tile_files(dir: &Path, stage: &str) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir.join("tiles").join(stage))
        .map(|r| r.flatten().map(|e| e.path()).collect())
        .unwrap_or_default();
    v.sort();
    v
}

#[test]
fn a_run_resumed_from_any_loss_writes_the_plain_runs_bytes() {
    let c = Case::new();
    ok(&strs(&c.reconstruct("plain.ply", &[])));
    let run = c.path("run");
    let with_dir = c.reconstruct("kept.ply", &["--run-dir", &run]);
    ok(&strs(&with_dir));
    same_file(&c.path("plain.ply"), &c.path("kept.ply"));
    let run_dir = Path::new(&run);
    let cubes = tile_files(run_dir, "marching-cubes");
    assert!(cubes.len() >= 8, "{} tiles", cubes.len());
    assert_eq!(tile_files(run_dir, "normals").len(), cubes.len());

    // Nothing left to do: the same bytes, and it says so.
    let said = ok(&strs(&with_dir));
    assert!(said.contains("nothing to do"), "{said}");

    // Lose the output, some tiles of each stage, the kept normals stage,
    // and damage one tile file: the rerun recomputes what is missing.
    std::fs::remove_file(c.path("kept.ply")).expect("rm");
    for stage in ["normals", "marching-cubes"] {
        for f in tile_files(run_dir, stage).iter().step_by(3) {
            std::fs::remove_file(f).expect("rm tile");
        }
    }
    std::fs::remove_dir_all(run_dir.join("stages")).ok();
    let victim = &tile_files(run_dir, "marching-cubes")[0];
    let mut bytes = std::fs::read(victim).expect("read tile");
    let last = bytes.len() - 1;
    bytes[last] ^= 0x55;
    std::fs::write(victim, bytes).expect("damage tile");
    std::fs::write(run_dir.join("tiles/normals/0000001.tmp-99999"), b"torn").expect("tmp");
    ok(&strs(&with_dir));
    same_file(&c.path("plain.ply"), &c.path("kept.ply"));
    assert!(!run_dir.join("tiles/normals/0000001.tmp-99999").exists());
}

#[test]
fn tile_jobs_in_any_order_write_the_plain_runs_bytes() {
    let c = Case::new();
    ok(&strs(&c.reconstruct("plain.ply", &[])));
    let run = c.path("jobs");
    // --emit records the run and prints its script without running it.
    let script = ok(&strs(&c.reconstruct(
        "jobs.ply",
        &["--run-dir", &run, "--emit", "parallel", "--tasks", "3"],
    )));
    assert!(
        script.contains("run-job") && script.contains("--share {}/3"),
        "{script}"
    );
    assert!(!Path::new(&c.path("jobs.ply")).exists());
    // A tile job before the store exists, or of an unknown stage, fails.
    fails_saying(
        &["run-job", &run, "--stage", "normals", "--share", "0/3"],
        "no store yet",
    );
    ok(&["run-job", &run, "--until", "normals", "-q"]);
    fails_saying(
        &[
            "run-job",
            &run,
            "--stage",
            "marching-cubes",
            "--share",
            "0/3",
            "-q",
        ],
        "tile jobs must finish",
    );
    for share in ["2/3", "0/3", "1/3", "1/3"] {
        ok(&[
            "run-job", &run, "--stage", "normals", "--share", share, "-q",
        ]);
    }
    ok(&["run-job", &run, "--until", "marching-cubes", "-q"]);
    ok(&[
        "run-job",
        &run,
        "--stage",
        "marching-cubes",
        "--tiles",
        "0-2",
        "-q",
    ]);
    // The last job computes the tiles no job did.
    ok(&["run-job", &run, "-q"]);
    same_file(&c.path("plain.ply"), &c.path("jobs.ply"));
    let status = ok(&["status", &run]);
    assert!(status.contains("output: written"), "{status}");
    assert!(status.contains("stage marching-cubes"), "{status}");
    fails_saying(
        &[
            "run-job", &run, "--stage", "no-such", "--share", "0/2", "-q",
        ],
        "no tile stage",
    );
}

#[test]
fn a_changed_input_or_command_line_is_refused_until_restart() {
    let c = Case::new();
    let run = c.path("run");
    ok(&strs(&c.reconstruct("a.ply", &["--run-dir", &run])));
    let other = c.reconstruct("a.ply", &["--run-dir", &run, "--min-piece", "0.5"]);
    fails_saying(&strs(&other), "--restart");
    let mut text = std::fs::read_to_string(&c.input).expect("read");
    text.push_str("0.5 0.5 0.5\n");
    std::fs::write(&c.input, text).expect("write");
    fails_saying(
        &strs(&c.reconstruct("a.ply", &["--run-dir", &run])),
        "changed since the run started",
    );
    fails_saying(&["run-job", &run, "-q"], "input changed");
    ok(&strs(
        &c.reconstruct("a.ply", &["--run-dir", &run, "--restart"]),
    ));
    // Threads, quiet and report are not part of a run.
    let report = c.path("r.json");
    let said = ok(&strs(&c.reconstruct(
        "a.ply",
        &["--run-dir", &run, "--threads", "1", "--report", &report],
    )));
    assert!(said.contains("nothing to do"), "{said}");
    // A directory holding something else is not taken over.
    let busy = c.path("busy");
    std::fs::create_dir(&busy).expect("mkdir");
    std::fs::write(Path::new(&busy).join("thesis.tex"), b"x").expect("write");
    fails_saying(
        &strs(&c.reconstruct("b.ply", &["--run-dir", &busy])),
        "not a scanmesh run directory",
    );
}

#[test]
fn normals_and_neighbours_resume_to_the_same_bytes() {
    let c = Case::new();
    for (cmd, out) in [("normals", "n.ply"), ("neighbors", "k.bin")] {
        let args = |name: &str, extra: &[&str]| -> Vec<String> {
            let mut a = vec![
                cmd.to_string(),
                c.input.clone(),
                "-o".into(),
                c.path(name),
                "--tile-points".into(),
                "2500".into(),
                "-q".into(),
            ];
            a.extend(extra.iter().map(|s| s.to_string()));
            a
        };
        ok(&strs(&args(out, &[])));
        let run = c.path(&format!("{cmd}-run"));
        let kept = format!("kept-{out}");
        ok(&strs(&args(&kept, &["--run-dir", &run])));
        same_file(&c.path(out), &c.path(&kept));
        std::fs::remove_file(c.path(&kept)).expect("rm");
        std::fs::remove_dir_all(Path::new(&run).join("stages")).ok();
        let stage = if cmd == "normals" {
            "normals"
        } else {
            "neighbours"
        };
        for f in tile_files(Path::new(&run), stage).iter().step_by(2) {
            std::fs::remove_file(f).expect("rm tile");
        }
        ok(&strs(&args(&kept, &["--run-dir", &run])));
        same_file(&c.path(out), &c.path(&kept));
    }
}

/// The script `--emit parallel` prints, run by GNU parallel (CI installs
/// it; elsewhere the test says it was skipped unless
/// `SCANMESH_REQUIRE_PARALLEL=1` makes it required).
#[test]
fn the_gnu_parallel_script_writes_the_plain_runs_bytes() {
    let have = Command::new("parallel").arg("--version").output().is_ok();
    if !have {
        assert!(
            std::env::var("SCANMESH_REQUIRE_PARALLEL").is_err(),
            "GNU parallel is required here but not installed"
        );
        eprintln!("skipped: GNU parallel is not installed");
        return;
    }
    let c = Case::new();
    ok(&strs(&c.reconstruct("plain.ply", &[])));
    let run = c.path("par");
    let script = ok(&strs(&c.reconstruct(
        "par.ply",
        &["--run-dir", &run, "--emit", "parallel", "--tasks", "4"],
    )));
    let path = c.path("job.sh");
    std::fs::write(&path, script).expect("write script");
    let o = Command::new("sh")
        .arg(&path)
        .env("SCANMESH", env!("CARGO_BIN_EXE_scanmesh"))
        .env("JOBS", "2")
        .output()
        .expect("run sh");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    same_file(&c.path("plain.ply"), &c.path("par.ply"));
}

/// SIGINT during the tile stage: exit 130, nothing temporary left beside
/// the output (the run directory keeps its finished tiles), and the rerun
/// resumes to the plain run's bytes.
#[test]
fn an_interrupted_run_leaves_nothing_behind_and_resumes() {
    let c = Case::new();
    ok(&strs(&c.reconstruct("plain.ply", &[])));
    let run = c.path("run");
    let args = c.reconstruct("out.ply", &["--run-dir", &run, "--threads", "1"]);
    let mut child = Command::new(env!("CARGO_BIN_EXE_scanmesh"))
        .args(&args)
        .spawn()
        .expect("spawn");
    let cubes = Path::new(&run).join("tiles/marching-cubes");
    let started = std::time::Instant::now();
    while tile_files(Path::new(&run), "marching-cubes").is_empty() {
        if child.try_wait().expect("wait").is_some() || started.elapsed().as_secs() > 120 {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
    let _ = std::fs::metadata(&cubes);
    let interrupted = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .expect("kill");
    assert!(interrupted.success());
    let status = child.wait().expect("wait");
    // The run may have finished before the signal arrived on a fast machine.
    if !Path::new(&c.path("out.ply")).exists() {
        assert_eq!(status.code(), Some(130), "{status:?}");
        let mut left: Vec<String> = std::fs::read_dir(&c.root)
            .expect("list")
            .flatten()
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .collect();
        left.sort();
        assert_eq!(
            left,
            ["plain.ply", "run", "sphere.xyz"],
            "left beside the output"
        );
    }
    ok(&strs(&args));
    same_file(&c.path("plain.ply"), &c.path("out.ply"));
}
