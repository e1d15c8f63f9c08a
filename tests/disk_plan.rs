//! The disk plan (`info --plan`, and the free-space check before a run)
//! against the disk runs use: the run directory's size sampled every few
//! milliseconds while `normals` and `reconstruct` (open and `--closed`) run
//! on generated scans of two shapes and on a real aerial LAZ. The peak must
//! never pass the plan, and the plan must not be so loose that a full disk
//! refuses runs that fit.

use scanmesh::memory::DiskPlan;
use scanmesh::normals::NormalParams;
use scanmesh::recon::implicit::reconstruct::ImplicitParams;
use scanmesh::units::human_bytes;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

/// Bytes of the files under `dir` (0 while it does not exist).
fn tree_bytes(dir: &Path) -> u64 {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return 0;
    };
    entries
        .flatten()
        .map(|e| match e.metadata() {
            Ok(m) if m.is_dir() => tree_bytes(&e.path()),
            Ok(m) => m.len(),
            Err(_) => 0,
        })
        .sum()
}

/// Runs `scanmesh args` and returns the largest size `dir` reached.
fn peak_while_running(args: &[String], dir: &Path) -> u64 {
    let done = AtomicBool::new(false);
    std::thread::scope(|s| {
        let sampler = s.spawn(|| {
            let mut peak = 0;
            while !done.load(Ordering::Relaxed) {
                peak = peak.max(tree_bytes(dir));
                std::thread::sleep(Duration::from_millis(2));
            }
            peak
        });
        let out = Command::new(env!("CARGO_BIN_EXE_scanmesh"))
            .args(args)
            .output()
            .expect("run scanmesh");
        done.store(true, Ordering::Relaxed);
        assert!(
            out.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        sampler.join().expect("sampler")
    })
}

/// Bytes whatever the points: headers, manifests, run records.
const FIXED: u64 = 1 << 20;

fn scangen(shape: &str, n: usize, out: &Path) {
    let status = Command::new(env!("CARGO_BIN_EXE_scangen"))
        .args([shape, "-n", &n.to_string(), "--noise-spacing", "0.1", "-o"])
        .arg(out)
        .status()
        .expect("run scangen");
    assert!(status.success());
}

#[test]
fn runs_stay_within_their_disk_plan() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let mut inputs: Vec<PathBuf> = Vec::new();
    for shape in ["terrain", "torus"] {
        let path = tmp.path().join(format!("{shape}.ply"));
        scangen(shape, 120_000, &path);
        inputs.push(path);
    }
    inputs
        .push(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/las/autzen_trim_cut.laz"));
    let closed = |closed| {
        ImplicitParams {
            closed,
            ..ImplicitParams::default()
        }
        .cost()
    };
    let runs = [
        ("normals", None, NormalParams::default().cost()),
        ("reconstruct", None, closed(false)),
        ("reconstruct", Some("--closed"), closed(true)),
    ];
    for input in &inputs {
        let reader =
            scanmesh::io::open_reader(input, scanmesh::io::ReadOptions::default()).expect("open");
        let info = reader.info();
        let points = info.declared_count.expect("a declared count");
        // A run directory keeps its checkpoints; a plain run's scratch
        // directory holds its store and spills only.
        let each = runs.iter().flat_map(|r| [(r, true), (r, false)]);
        for ((command, flag, cost), in_run_dir) in each {
            // Neither run keeps anything of its input once its store is
            // built: normals reads it again, the implicit mesh needs none.
            let kept = scanmesh::store::Kept::Nothing;
            let store = scanmesh::store::store_bytes_per_point(info, kept).expect("store bytes");
            let run_dir = tmp.path().join("run");
            if !in_run_dir {
                std::fs::create_dir_all(&run_dir).expect("scratch directory");
            }
            let out = tmp.path().join("out.ply");
            let mut args: Vec<String> = vec![
                command.to_string(),
                input.display().to_string(),
                "-q".into(),
                "-o".into(),
                out.display().to_string(),
                if in_run_dir {
                    "--run-dir"
                } else {
                    "--scratch-dir"
                }
                .into(),
                run_dir.display().to_string(),
            ];
            args.extend(flag.map(str::to_string));
            let peak = peak_while_running(&args, &run_dir);
            let cost = match in_run_dir {
                true => cost.in_run_dir(),
                false => *cost,
            };
            let plan = DiskPlan::new(points, store, &cost).scratch_dir();
            let what = format!(
                "{} {command} {flag:?} run dir {in_run_dir}",
                input.display()
            );
            eprintln!("{what}: peak {peak} B, plan {plan} B");
            assert!(
                peak <= plan + FIXED,
                "{what}: peak {peak} B over the plan's {plan} B"
            );
            assert!(
                4 * peak >= plan,
                "{what}: peak {peak} B, plan {plan} B: too loose"
            );
            let written = std::fs::metadata(&out).expect("output").len();
            let planned = DiskPlan::new(points, store, &cost).output;
            assert!(
                written <= planned + FIXED && 4 * written >= planned,
                "{what}: output {written} B, planned {planned} B"
            );
            std::fs::remove_dir_all(&run_dir).ok();
            std::fs::remove_file(&out).ok();
        }
    }
}

/// A LAS or LAZ output of an input of its own format is planned from the
/// input file's bytes per point, not from a PLY row: on the real LAZ and
/// LAS fixtures the output is within the plan, and the plan within 2x.
#[test]
fn a_las_output_is_planned_from_its_input() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let fixtures = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/las");
    let declared = NormalParams::default().cost().output_per_point;
    for name in [
        "autzen_trim_cut.laz",
        "32-1-472-150-76.laz",
        "autzen_town_cut.las",
    ] {
        let input = fixtures.join(name);
        let reader =
            scanmesh::io::open_reader(&input, scanmesh::io::ReadOptions::default()).expect("open");
        let info = reader.info();
        let points = info.declared_count.expect("a declared count");
        let out = tmp.path().join(name);
        let per_point = scanmesh::store::output_bytes_per_point(info, &out, declared);
        let ply =
            scanmesh::store::output_bytes_per_point(info, &out.with_extension("ply"), declared);
        assert_eq!(ply, declared, "{name}");
        // `info --plan -o` plans the output as the run will.
        for (output, bytes) in [(&out, per_point), (&out.with_extension("ply"), declared)] {
            let o = Command::new(env!("CARGO_BIN_EXE_scanmesh"))
                .args(["info", "-q", "--plan", "-o"])
                .arg(output)
                .arg(&input)
                .output()
                .expect("run scanmesh info");
            let text = String::from_utf8_lossy(&o.stdout);
            let figure = format!("the output {} and", human_bytes(points * bytes));
            assert!(
                text.contains(&figure),
                "{name} -o {}: {text}",
                output.display()
            );
            // And whether this disk has room for it now (these have).
            assert!(text.contains("room on disk: "), "{name}: {text}");
            assert!(text.contains("has it now"), "{name}: {text}");
        }
        let status = Command::new(env!("CARGO_BIN_EXE_scanmesh"))
            .arg("normals")
            .arg(&input)
            .arg("-o")
            .arg(&out)
            .arg("-q")
            .status()
            .expect("run scanmesh");
        assert!(status.success(), "{name}");
        let written = std::fs::metadata(&out).expect("output").len();
        let planned = points * per_point;
        eprintln!("{name}: written {written} B, planned {planned} B ({per_point} B a point)");
        assert!(
            written <= planned + FIXED,
            "{name}: {written} B over {planned}"
        );
        assert!(
            2 * written >= planned,
            "{name}: {written} B, planned {planned}"
        );
    }
}

/// `--scratch` refuses a run whose plan needs more, before it reads the
/// input; with a `--cell` in the input's units the mesh's share is known
/// only once the store is built, and is refused then, before any tile runs.
#[test]
fn a_scratch_limit_refuses_runs_that_need_more() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let input = tmp.path().join("terrain.ply");
    scangen("terrain", 120_000, &input);
    let out = tmp.path().join("out.ply");
    let run = |args: &[&str]| {
        let o = Command::new(env!("CARGO_BIN_EXE_scanmesh"))
            .args(args)
            .arg(&input)
            .arg("-o")
            .arg(&out)
            .arg("-q")
            .output()
            .expect("run scanmesh");
        (
            o.status.success(),
            String::from_utf8_lossy(&o.stderr).to_string(),
        )
    };
    // The store and the normals' scratch: about 15 MB for 120k points.
    let (ok, err) = run(&["normals", "--scratch", "4MiB"]);
    assert!(!ok && err.contains("--scratch 4.00MiB"), "{err}");
    assert!(err.contains("needs about"), "{err}");
    assert!(!out.exists());
    let (ok, err) = run(&["normals", "--scratch", "64MiB"]);
    assert!(ok, "{err}");
    std::fs::remove_file(&out).ok();
    // A cell of about 2 spacings: in a run directory, which keeps the
    // mesh's tiles, the mesh's share (some 36 MB) passes the first check,
    // which cannot count it, and not the second. A plain run streams the
    // tiles to the writer, beside the output: the limit does not see them.
    let run_dir = |name: &str| tmp.path().join(name).display().to_string();
    let (a, b) = (run_dir("a"), run_dir("b"));
    let cell = ["reconstruct", "--cell", "0.3", "--scratch"];
    let (ok, err) = run(&[&cell[..], &["25MiB", "--run-dir", &a]].concat());
    assert!(!ok && err.contains("--scratch 25.0MiB"), "{err}");
    assert!(!out.exists());
    let (ok, err) = run(&[&cell[..], &["80MiB", "--run-dir", &b]].concat());
    assert!(ok, "{err}");
    std::fs::remove_file(&out).ok();
    let (ok, err) = run(&[&cell[..], &["25MiB"]].concat());
    assert!(ok, "{err}");
    // A command with nothing to plan says so rather than ignore the limit.
    std::fs::remove_file(&out).ok();
    let o = Command::new(env!("CARGO_BIN_EXE_scanmesh"))
        .arg("convert")
        .arg(&input)
        .arg(&out)
        .args(["--scratch", "1GiB"])
        .output()
        .expect("run scanmesh");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("writes no planned scratch"),
        "{err}"
    );
    assert!(!out.exists());
}
