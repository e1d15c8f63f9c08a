//! Resumable runs (`--run-dir`), tile jobs (`run-job`) and job scripts
//! (`--emit`): whatever order the parts run in, whatever was lost on the
//! way (tiles, a damaged tile file, the output), the result is byte for
//! byte the one a plain run writes; a changed input or command line is
//! refused.

use glam::DVec3;
use scanmesh::synth::fibonacci::fibonacci_sphere;
use std::path::{Path, PathBuf};
use std::process::Command;

mod common;
use common::scanmesh;

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

/// A directory name that breaks a shell script quoting paths carelessly:
/// blanks, a quote, `$`, GNU parallel's `{}` and Slurm's `%`.
const ODD: &str = "odd dir's $HOME {} 100%";

impl Case {
    /// A 20,000-point sphere with a bump (so the tiles differ), as XYZ.
    fn new() -> Case {
        Case::under("")
    }

    /// The case with its input, outputs and run directories in `sub`.
    fn under(sub: &str) -> Case {
        let dir = tempfile::tempdir().expect("tmp");
        let root = dir.path().join(sub);
        std::fs::create_dir_all(&root).expect("mkdir");
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
/// `SCANMESH_REQUIRE_PARALLEL=1` makes it required), on paths a careless
/// script splits, with no `SCANMESH` and no scanmesh on PATH: it runs the
/// binary that wrote it.
#[test]
fn the_gnu_parallel_script_writes_the_plain_runs_bytes_on_odd_paths() {
    let have = Command::new("parallel").arg("--version").output().is_ok();
    if !have {
        assert!(
            std::env::var("SCANMESH_REQUIRE_PARALLEL").is_err(),
            "GNU parallel is required here but not installed"
        );
        eprintln!("skipped: GNU parallel is not installed");
        return;
    }
    let c = Case::under(ODD);
    ok(&strs(&c.reconstruct("plain.ply", &[])));
    let run = c.path("par run");
    let script = ok(&strs(&c.reconstruct(
        "par out.ply",
        &["--run-dir", &run, "--emit", "parallel", "--tasks", "4"],
    )));
    assert!(script.contains(&default_binary_line()), "{script}");
    let path = c.path("job.sh");
    std::fs::write(&path, script).expect("write script");
    let o = Command::new("sh")
        .arg(&path)
        .env_remove("SCANMESH")
        .env("PATH", "/usr/local/bin:/usr/bin:/bin")
        .env("JOBS", "2")
        .output()
        .expect("run sh");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    same_file(&c.path("plain.ply"), &c.path("par out.ply"));
}

/// The line of an emitted script that makes the emitting binary the
/// default `SCANMESH`.
fn default_binary_line() -> String {
    let exe = std::fs::canonicalize(env!("CARGO_BIN_EXE_scanmesh")).expect("binary");
    format!("SCANMESH=${{SCANMESH:-'{}'}}", exe.display())
}

/// A fake `sbatch` on PATH: each job runs at once, in submission order,
/// as Slurm runs it (the `--wrap` text as a sh script, once per array task
/// with `SLURM_ARRAY_TASK_ID`, its output to `--output` with `%A`, `%a` and
/// `%%` expanded); a job after a failed one does not run. Prints its job
/// id as `--parsable` does on a named cluster (`ID;CLUSTER`).
const FAKE_SBATCH: &str = r#"#!/bin/bash
set -u
state=${FAKE_SLURM_STATE:?}
wrap='' array='' output='' dep=''
for a in "$@"; do
  case $a in
    --wrap=*) wrap=${a#--wrap=} ;;
    --array=*) array=${a#--array=} ;;
    --output=*) output=${a#--output=} ;;
    --dependency=afterok:*) dep=${a#--dependency=afterok:} ;;
  esac
done
id=$(( $(cat "$state/next" 2>/dev/null || echo 100) + 1 ))
echo "$id" > "$state/next"
if [ -n "$dep" ] && [ -e "$state/failed-$dep" ]; then
  touch "$state/failed-$id"
else
  printf '#!/bin/sh
%s
' "$wrap" > "$state/job-$id.sh"
  tasks=4294967294
  if [ -n "$array" ]; then tasks=$(seq "${array%-*}" "${array#*-}"); fi
  for t in $tasks; do
    o=${output//'%%'/$''}; o=${o//'%A'/$id}; o=${o//'%a'/$t}; o=${o//$''/%}
    SLURM_ARRAY_TASK_ID=$t sh "$state/job-$id.sh" > "$o" 2>&1 || touch "$state/failed-$id"
  done
fi
echo "$id;local"
"#;

/// A directory holding an executable `sbatch` with `body`, for PATH.
fn fake_sbatch(c: &Case, name: &str, body: &str) -> String {
    use std::os::unix::fs::PermissionsExt;
    let bin = c.path(name);
    std::fs::create_dir_all(&bin).expect("mkdir");
    let sbatch = Path::new(&bin).join("sbatch");
    std::fs::write(&sbatch, body).expect("write sbatch");
    std::fs::set_permissions(&sbatch, std::fs::Permissions::from_mode(0o755)).expect("chmod");
    format!("{bin}:{}", std::env::var("PATH").unwrap_or_default())
}

/// The script `--emit slurm` prints, submitted to a fake `sbatch` that
/// runs the jobs as Slurm would, on odd paths, with `SCANMESH` naming the
/// binary by an odd path too: each `--wrap` text survives being parsed
/// again by sh, each job writes its log where `--output` says, and the
/// result is the plain run's bytes.
#[test]
fn the_slurm_script_writes_the_plain_runs_bytes_on_odd_paths() {
    let c = Case::under(ODD);
    let normals = |out: &str, extra: &[&str]| -> Vec<String> {
        let mut a = vec![
            "normals".to_string(),
            c.input.clone(),
            "-o".into(),
            c.path(out),
            "--tile-points".into(),
            "2500".into(),
            "-q".into(),
        ];
        a.extend(extra.iter().map(|s| s.to_string()));
        a
    };
    ok(&strs(&normals("plain.ply", &[])));
    let run = c.path("slurm run");
    let script = ok(&strs(&normals(
        "slurm out.ply",
        &["--run-dir", &run, "--emit", "slurm", "--tasks", "3"],
    )));
    assert!(script.contains(&default_binary_line()), "{script}");
    let path = c.path("job.sh");
    std::fs::write(&path, script).expect("write script");
    let state = c.path("slurm state");
    std::fs::create_dir(&state).expect("mkdir");
    // The binary by another odd name, through SCANMESH.
    let bin_dir = c.path("bin's dir");
    std::fs::create_dir(&bin_dir).expect("mkdir");
    let binary = Path::new(&bin_dir).join("scan mesh");
    std::os::unix::fs::symlink(env!("CARGO_BIN_EXE_scanmesh"), &binary).expect("symlink");
    let o = Command::new("bash")
        .arg(&path)
        .env("PATH", fake_sbatch(&c, "fake bin", FAKE_SBATCH))
        .env("FAKE_SLURM_STATE", &state)
        .env("SCANMESH", &binary)
        .output()
        .expect("run bash");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    // The last job's id: 1 single job, 1 array, 1 single job.
    assert_eq!(String::from_utf8_lossy(&o.stdout).trim(), "103", "{err}");
    let failed: Vec<String> = std::fs::read_dir(&state)
        .expect("list")
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with("failed-"))
        .collect();
    assert!(failed.is_empty(), "jobs failed: {failed:?}");
    for log in [
        "slurm-101_4294967294.out",
        "slurm-102_2.out",
        "slurm-103_4294967294.out",
    ] {
        assert!(Path::new(&run).join(log).exists(), "no {log} in {run}");
    }
    same_file(&c.path("plain.ply"), &c.path("slurm out.ply"));
}

/// A submission that fails, or gives no job id, stops the Slurm script
/// with an error: the jobs after it would run without the work they need.
#[test]
fn a_failed_submission_fails_the_slurm_script() {
    let c = Case::new();
    let run = c.path("run");
    let script = ok(&strs(&c.reconstruct(
        "out.ply",
        &["--run-dir", &run, "--emit", "slurm", "--tasks", "2"],
    )));
    let path = c.path("job.sh");
    std::fs::write(&path, script).expect("write script");
    for (name, sbatch, says) in [
        (
            "refusing",
            "#!/bin/sh
echo 'sbatch: error: invalid partition' >&2
exit 1
",
            "sbatch failed",
        ),
        (
            "chatty",
            "#!/bin/sh
echo 'Submitted batch job 17'
",
            "gave no job id",
        ),
        (
            "silent",
            "#!/bin/sh
",
            "gave no job id",
        ),
    ] {
        let o = Command::new("bash")
            .arg(&path)
            .env("PATH", fake_sbatch(&c, name, sbatch))
            .output()
            .expect("run bash");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{name} sbatch: the script succeeded");
        assert!(err.contains(says), "{name} sbatch: {err}");
        assert!(o.stdout.is_empty(), "{name} sbatch: printed a job id");
    }
}

/// `status` of a run whose process died says so, with no time left, and
/// the output line checks the file the run wrote.
#[test]
fn status_names_a_dead_process_and_a_lost_output() {
    let c = Case::new();
    let run = c.path("run");
    let args = |extra: &[&str]| -> Vec<String> {
        let mut a = vec![
            "normals".to_string(),
            c.input.clone(),
            "-o".into(),
            c.path("n.ply"),
            "--tile-points".into(),
            "1000".into(),
            "-q".into(),
            "--run-dir".into(),
            run.clone(),
        ];
        a.extend(extra.iter().map(|s| s.to_string()));
        a
    };
    ok(&strs(&args(&["--emit", "parallel"])));
    ok(&["run-job", &run, "--until", "normals", "-q"]);
    ok(&[
        "run-job", &run, "--stage", "normals", "--share", "0/2", "-q",
    ]);
    // A process that started the other half, then was killed.
    let mut child = Command::new("sleep").arg("60").spawn().expect("sleep");
    let pid = child.id();
    let log = Path::new(&run).join("log.txt");
    let mut text = std::fs::read_to_string(&log).expect("log");
    text += &format!("1 pid {pid} start job --stage normals --share 1/2\n");
    std::fs::write(&log, text).expect("write log");
    let status = ok(&["status", &run]);
    assert!(
        status.contains(&format!("running (process {pid})")),
        "{status}"
    );
    child.kill().expect("kill");
    child.wait().expect("wait");
    let status = ok(&["status", &run]);
    assert!(
        status.contains(&format!("stopped (process {pid} is gone)")),
        "{status}"
    );
    assert!(
        !status.contains(" left"),
        "a time left for a stopped run: {status}"
    );
    // The rerun takes its work over, and writes the output.
    ok(&strs(&args(&[])));
    let status = ok(&["status", &run]);
    assert!(status.contains("state: finished"), "{status}");
    assert!(status.contains("output: written"), "{status}");
    std::fs::remove_file(c.path("n.ply")).expect("rm");
    let status = ok(&["status", &run]);
    assert!(!status.contains("output: written"), "{status}");
    assert!(status.contains("is gone"), "{status}");
    std::fs::write(c.path("n.ply"), b"not the run's").expect("write");
    let status = ok(&["status", &run]);
    assert!(
        status.contains("changed since the run wrote it"),
        "{status}"
    );
}

/// A reader that stops early (`scanmesh status DIR | head -1`) ends the
/// command quietly and successfully, whichever command prints.
#[test]
fn a_closed_stdout_ends_the_command_quietly() {
    let c = Case::new();
    let run = c.path("run");
    let emit = c.reconstruct("out.ply", &["--run-dir", &run, "--emit", "slurm"]);
    ok(&strs(&emit));
    for args in [
        vec!["status".to_string(), run.clone()],
        vec!["info".to_string(), c.input.clone()],
        emit,
    ] {
        let (reader, writer) = std::io::pipe().expect("pipe");
        drop(reader);
        let o = Command::new(env!("CARGO_BIN_EXE_scanmesh"))
            .args(&args)
            .stdout(writer)
            .output()
            .expect("run scanmesh");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success(), "{args:?}: {:?} {err}", o.status);
        assert!(err.is_empty(), "{args:?} said: {err}");
    }
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
