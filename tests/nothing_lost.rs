//! Nothing lost, nothing silently wrong (issue 37): a run directory is
//! only ever cleared of what scanmesh made; points come out with the
//! input's coordinates exactly (f64 in, the same f64 out; LAS in and out,
//! the same integers); a store or run directory changed behind scanmesh's
//! back is refused, naming the file and the tile. Outputs are read here by
//! the tests' own PLY parser and by the `las` crate's raw records, not by
//! scanmesh's readers.

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

fn fails_saying(args: &[&str], words: &[&str]) -> String {
    let o = scanmesh(args);
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(!o.status.success(), "scanmesh {args:?} succeeded");
    for w in words {
        assert!(err.contains(w), "error does not say `{w}`: {err}");
    }
    assert!(!err.contains("panicked"), "panic: {err}");
    err
}

fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .expect("list")
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// A 200 km x 200 km wavy surface at UTM-like coordinates, millimetres.
fn utm_points(n: usize, seed: u64) -> Vec<[f64; 3]> {
    let mut rng = scanmesh::synth::Rng::new(seed);
    let mm = |v: f64| (v * 1000.0).round() / 1000.0;
    (0..n)
        .map(|_| {
            let x = mm(300_000.0 + 200_000.0 * rng.uniform());
            let y = mm(5_000_000.0 + 200_000.0 * rng.uniform());
            let z = mm(100.0 + 50.0 * (x / 7000.0).sin() + 30.0 * (y / 9000.0).cos());
            [x, y, z]
        })
        .collect()
}

fn write_xyz(path: &Path, pts: &[[f64; 3]]) {
    let text: String = pts
        .iter()
        .map(|p| format!("{:.3} {:.3} {:.3}\n", p[0], p[1], p[2]))
        .collect();
    std::fs::write(path, text).expect("write xyz");
}

/// x y z of every vertex of a binary little-endian PLY, as f64 (the
/// test's own parser: any layout, x y z as float or double).
fn ply_xyz(path: &Path) -> Vec<[f64; 3]> {
    let bytes = std::fs::read(path).expect("read ply");
    let end = b"end_header\n";
    let at = bytes
        .windows(end.len())
        .position(|w| w == end)
        .expect("header")
        + end.len();
    let header = String::from_utf8_lossy(&bytes[..at]);
    assert!(header.contains("binary_little_endian"), "{header}");
    let (mut count, mut props) = (0usize, Vec::new());
    for line in header.lines() {
        let w: Vec<&str> = line.split_whitespace().collect();
        match w.as_slice() {
            ["element", "vertex", n] => count = n.parse().expect("count"),
            ["element", ..] if count > 0 => break,
            ["property", ty, name] => props.push((ty.to_string(), name.to_string())),
            _ => {}
        }
    }
    let size = |t: &str| match t {
        "char" | "uchar" | "int8" | "uint8" => 1,
        "short" | "ushort" | "int16" | "uint16" => 2,
        "int" | "uint" | "float" | "int32" | "uint32" | "float32" => 4,
        _ => 8,
    };
    let record: usize = props.iter().map(|(t, _)| size(t)).sum();
    let field = |name: &str| {
        let k = props.iter().position(|(_, n)| n == name).expect(name);
        let off: usize = props[..k].iter().map(|(t, _)| size(t)).sum();
        (off, props[k].0.clone())
    };
    let fields = ["x", "y", "z"].map(field);
    (0..count)
        .map(|i| {
            let r = &bytes[at + i * record..at + (i + 1) * record];
            fields.clone().map(|(o, t)| match t.as_str() {
                "double" | "float64" => f64::from_le_bytes(r[o..o + 8].try_into().expect("8")),
                _ => f32::from_le_bytes(r[o..o + 4].try_into().expect("4")) as f64,
            })
        })
        .collect()
}

/// A LAS 1.2 file of `pts` at scale 0.001 and a whole-metre offset,
/// written by the `las` crate.
fn write_las(path: &Path, pts: &[[f64; 3]]) {
    let mut b = las::Builder::from((1, 2));
    b.point_format = las::point::Format::new(1).expect("format");
    b.transforms = las::Vector {
        x: las::Transform {
            scale: 0.001,
            offset: 400_000.0,
        },
        y: las::Transform {
            scale: 0.001,
            offset: 5_100_000.0,
        },
        z: las::Transform {
            scale: 0.001,
            offset: 0.0,
        },
    };
    let header = b.into_header().expect("header");
    let mut w = las::Writer::from_path(path, header).expect("las writer");
    for (i, p) in pts.iter().enumerate() {
        w.write_point(las::Point {
            x: p[0],
            y: p[1],
            z: p[2],
            intensity: i as u16,
            gps_time: Some(i as f64 * 0.5),
            ..Default::default()
        })
        .expect("write point");
    }
    w.close().expect("close");
}

/// The raw integers and transforms of a LAS file's records.
fn las_raw(path: &Path) -> (Vec<[i32; 3]>, [f64; 6]) {
    let mut r = las::Reader::from_path(path).expect("las reader");
    let t = *r.header().transforms();
    // Every point format starts with X, Y, Z as i32.
    let data = r.read_all().expect("points");
    let ints = data
        .raw_bytes()
        .chunks_exact(data.record_len())
        .map(|rec| [0, 4, 8].map(|o| i32::from_le_bytes(rec[o..o + 4].try_into().expect("4"))))
        .collect();
    let tf = [
        t.x.scale, t.y.scale, t.z.scale, t.x.offset, t.y.offset, t.z.offset,
    ];
    (ints, tf)
}

#[test]
fn restart_clears_only_what_scanmesh_made() {
    let dir = tempfile::tempdir().expect("tmp");
    let home = dir.path().join("home");
    std::fs::create_dir(&home).expect("mkdir");
    let input = home.join("in.xyz");
    write_xyz(&input, &utm_points(3000, 1));
    std::fs::write(home.join("notes.txt"), b"a user's file").expect("notes");
    let out = home.join("out.ply");
    // `--run-dir .` (here: the input's directory) with --restart: refused,
    // nothing deleted.
    let args = ["normals", s(&input), "-o", s(&out), "-q", "--run-dir"];
    let err = fails_saying(
        &[&args[..], &[s(&home), "--restart"]].concat(),
        &["not a scanmesh run directory", "deletes only what it made"],
    );
    assert!(err.contains(s(&home)), "{err}");
    assert_eq!(names(&home), ["in.xyz", "notes.txt"]);
    // A run directory scanmesh made: --restart keeps what the user put there.
    let run = dir.path().join("run");
    ok(&[&args[..], &[s(&run)]].concat());
    std::fs::write(run.join("mine.txt"), b"keep me").expect("mine");
    ok(&[&args[..], &[s(&run), "--restart"]].concat());
    assert!(
        run.join("mine.txt").is_file(),
        "--restart removed a user's file"
    );
    assert!(run.join("store").is_dir());
}

#[test]
fn a_missing_input_leaves_no_run_directory() {
    let dir = tempfile::tempdir().expect("tmp");
    let run = dir.path().join("run");
    let out = dir.path().join("o.ply");
    let missing = dir.path().join("nope.xyz");
    fails_saying(
        &["normals", s(&missing), "-o", s(&out), "--run-dir", s(&run)],
        &["nope.xyz"],
    );
    assert!(!run.exists(), "an empty run directory was left");
}

#[test]
fn normals_and_curvature_write_the_inputs_coordinates_exactly() {
    let dir = tempfile::tempdir().expect("tmp");
    for seed in [1, 2] {
        let pts = utm_points(20_000, seed);
        let xyz = dir.path().join("utm.xyz");
        write_xyz(&xyz, &pts);
        // What the text holds, parsed as f64 by the standard library.
        let want: Vec<[f64; 3]> = std::fs::read_to_string(&xyz)
            .expect("read")
            .lines()
            .map(|l| {
                let v: Vec<f64> = l.split(' ').map(|t| t.parse().expect("f64")).collect();
                [v[0], v[1], v[2]]
            })
            .collect();
        for (command, out) in [("normals", "n.ply"), ("curvature", "k.ply")] {
            let out = dir.path().join(out);
            let tiles = ["--tile-points", "3000"];
            ok(&[&[command, s(&xyz), "-o", s(&out), "-q"][..], &tiles].concat());
            assert!(
                ply_xyz(&out) == want,
                "{command}, seed {seed}: coordinates moved"
            );
        }
        // LAS at 1 mm: the same integers under the same scale and offset.
        let las_in = dir.path().join("utm.las");
        write_las(&las_in, &pts);
        let (ints, tf) = las_raw(&las_in);
        let las_out = dir.path().join("n.las");
        ok(&["normals", s(&las_in), "-o", s(&las_out), "-q"]);
        let (got, got_tf) = las_raw(&las_out);
        assert_eq!(got_tf, tf, "seed {seed}: the LAS transform changed");
        assert!(got == ints, "seed {seed}: LAS integers changed");
        // LAS in, f64 out: the f64 the LAS integers make.
        let ply = dir.path().join("nl.ply");
        ok(&["curvature", s(&las_in), "-o", s(&ply), "-q"]);
        let decoded: Vec<[f64; 3]> = ints
            .iter()
            .map(|i| [0, 1, 2].map(|a| tf[a] * f64::from(i[a]) + tf[3 + a]))
            .collect();
        assert!(
            ply_xyz(&ply) == decoded,
            "seed {seed}: LAS to PLY moved points"
        );
    }
}

/// Flips one byte of `path` at `at` (a fraction of its length).
fn flip(path: &Path, at: f64) -> Vec<u8> {
    let bytes = std::fs::read(path).expect("read");
    let mut damaged = bytes.clone();
    let k = ((bytes.len() - 1) as f64 * at) as usize;
    damaged[k] ^= 0x10;
    std::fs::write(path, damaged).expect("damage");
    bytes
}

#[test]
fn a_flipped_byte_in_any_store_column_is_refused() {
    let dir = tempfile::tempdir().expect("tmp");
    let las_in = dir.path().join("in.las");
    write_las(&las_in, &utm_points(6000, 3));
    let store = dir.path().join("s");
    ok(&[
        "tile",
        s(&las_in),
        "-o",
        s(&store),
        "-q",
        "--tile-points",
        "1000",
    ]);
    let out = dir.path().join("n.ply");
    // Normals first, so the store holds computed columns too.
    ok(&["normals", s(&store), "-o", s(&out), "-q"]);
    let mut columns: Vec<PathBuf> = std::fs::read_dir(&store)
        .expect("list")
        .flatten()
        .map(|e| e.path())
        .filter(|p| {
            !p.file_name()
                .is_some_and(|n| n.to_string_lossy().starts_with('.'))
        })
        .collect();
    columns.sort();
    let listed: Vec<String> = columns
        .iter()
        .map(|p| p.file_name().expect("name").to_string_lossy().into_owned())
        .collect();
    for want in [
        "xyz.f32",
        "index.u32",
        "blocks.f32",
        "xyz.input",
        "normal.f32",
        "flags.u8",
    ] {
        assert!(listed.iter().any(|n| n == want), "{want} not in {listed:?}");
    }
    for column in &columns {
        for at in [0.0, 0.37, 1.0] {
            let good = flip(column, at);
            let name = column
                .file_name()
                .expect("name")
                .to_string_lossy()
                .into_owned();
            // A manifest that no longer parses is refused as such.
            let err = fails_saying(&["normals", s(&store), "-o", s(&out), "-q"], &[&name]);
            assert!(
                err.contains("damaged") || err.contains("not a valid point store"),
                "{name} at {at}: {err}"
            );
            std::fs::write(column, good).expect("restore");
        }
    }
    ok(&["normals", s(&store), "-o", s(&out), "-q"]);
}

#[test]
fn a_run_directory_changed_behind_the_runs_back_is_not_done() {
    let dir = tempfile::tempdir().expect("tmp");
    let input = dir.path().join("in.xyz");
    write_xyz(&input, &utm_points(8000, 4));
    let out = dir.path().join("n.ply");
    let run = dir.path().join("run");
    let args = [
        "normals",
        s(&input),
        "-o",
        s(&out),
        "--run-dir",
        s(&run),
        "--tile-points",
        "2000",
    ];
    ok(&args);
    let first = std::fs::read(&out).expect("output");
    assert!(ok(&args).contains("nothing to do"));
    // A damaged column of the run's store: refused, not "nothing to do".
    let good = flip(&run.join("store/xyz.f32"), 0.5);
    fails_saying(&args, &["xyz.f32", "damaged", "tile"]);
    std::fs::write(run.join("store/xyz.f32"), good).expect("restore");
    // An output replaced behind the run's back is written again.
    std::fs::write(&out, b"something else").expect("replace");
    let said = ok(&args);
    assert!(!said.contains("nothing to do"), "{said}");
    assert!(std::fs::read(&out).expect("output") == first);
    // A damaged run file is refused, naming it.
    let good = flip(&run.join("run.json"), 0.5);
    fails_saying(&args, &["run.json"]);
    std::fs::write(run.join("run.json"), good).expect("restore");
    // A deleted manifest: refused, not rebuilt over, not "nothing to do".
    std::fs::remove_file(run.join("store/manifest.json")).expect("rm");
    fails_saying(&args, &["manifest.json", "--restart"]);
    ok(&[&args[..], &["--restart"]].concat());
    assert!(std::fs::read(&out).expect("output") == first);
}

/// SIGKILL (the OOM killer, a scheduler's limit) runs no cleanup: the
/// scratch store stays; the next run in that place reclaims it, and never
/// touches the scratch of a run that is alive.
#[test]
fn scratch_a_killed_run_left_is_reclaimed_by_the_next() {
    let dir = tempfile::tempdir().expect("tmp");
    let input = dir.path().join("big.xyz");
    write_xyz(&input, &utm_points(400_000, 5));
    let small = dir.path().join("small.xyz");
    write_xyz(&small, &utm_points(3000, 6));
    let out = dir.path().join("n.ply");
    let scratch = |dir: &Path| -> Vec<String> {
        names(dir)
            .into_iter()
            .filter(|n| n.starts_with(".n.ply.") || n.starts_with(".m.ply."))
            .collect()
    };
    let mut child = Command::new(env!("CARGO_BIN_EXE_scanmesh"))
        .args(["normals", s(&input), "-o", s(&out), "-q", "--threads", "1"])
        .stdout(std::process::Stdio::null())
        .spawn()
        .expect("spawn");
    let started = std::time::Instant::now();
    // Killed once its build has begun (its scratch store holds a column).
    let building = || {
        scratch(dir.path())
            .iter()
            .any(|n| dir.path().join(n).join("xyz.input").exists())
    };
    while !building() && started.elapsed().as_secs() < 60 {
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    // A second run in the same place, alive while the first is killed
    // (its own reclaiming, before it made its scratch, found a live run).
    let live_out = dir.path().join("m.ply");
    let mut live = Command::new(env!("CARGO_BIN_EXE_scanmesh"))
        .args([
            "normals",
            s(&input),
            "-o",
            s(&live_out),
            "-q",
            "--threads",
            "1",
        ])
        .stdout(std::process::Stdio::null())
        .spawn()
        .expect("spawn");
    while !scratch(dir.path()).iter().any(|n| n.starts_with(".m.ply.")) {
        assert!(
            started.elapsed().as_secs() < 60,
            "the live run made no scratch"
        );
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    child.kill().expect("kill -9");
    child.wait().expect("wait");
    let left = scratch(dir.path());
    assert!(
        left.iter().any(|n| n.starts_with(".n.ply.store-")),
        "{left:?}"
    );
    let o = scanmesh(&["normals", s(&small), "-o", s(&dir.path().join("x.ply"))]);
    let said = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{said}");
    assert!(said.contains("killed runs left"), "{said}");
    let now = scratch(dir.path());
    assert!(
        !now.iter().any(|n| n.starts_with(".n.ply.")),
        "left: {now:?}"
    );
    assert!(live.wait().expect("wait").success(), "the live run failed");
    assert!(live_out.is_file());
    assert!(scratch(dir.path()).is_empty(), "{:?}", scratch(dir.path()));
}

/// The checkpoint fuzzer's first finding: a saved normals tile whose
/// checksum is right but whose forest names point 12,692 of a 2,000-point
/// store (a panic in the orientation's union-find). A saved result that
/// does not fit its tile is recomputed, and the run says so.
#[test]
fn a_saved_tile_that_does_not_fit_its_tile_is_recomputed() {
    use glam::DVec3;
    use scanmesh::io::memory::MemoryReader;
    use scanmesh::normals::{compute_normals, NormalParams};
    use scanmesh::pipeline::{NoProgress, RunOptions};
    use scanmesh::store::{build_store, BuildOptions, Checkpoints, Job, TileTarget, NORMALS};
    let found = std::fs::read("tests/fixtures/fuzz/checkpoint_forged_edge.bin").expect("fixture");
    let payload = &found[1..];
    let dir = tempfile::tempdir().expect("tmp");
    let pts = scanmesh::synth::fibonacci::fibonacci_sphere(DVec3::ZERO, 1.0, 2000);
    let opts = BuildOptions {
        tiles: TileTarget::Points(500),
        ..BuildOptions::default()
    };
    let normals_of = |store_dir: &Path, keep: Option<&Path>| {
        let mut reader = MemoryReader::new("sphere", pts.clone(), None);
        let mut store = build_store(&mut reader, store_dir, &opts, &NoProgress).expect("store");
        let checkpoints = keep.map(|k| Checkpoints::new(k, Job::Whole));
        if let Some(c) = &checkpoints {
            store.keep_tiles(c.clone());
        }
        compute_normals(
            &mut store,
            &NormalParams::default(),
            RunOptions::new(1),
            &NoProgress,
        )
        .expect("normals");
        let column = store.column(&NORMALS).expect("column");
        let mut n = Vec::new();
        column.read_f32(0, store.len(), &mut n).expect("read");
        (n, checkpoints.map(|c| c.damaged()).unwrap_or_default())
    };
    let (clean, _) = normals_of(&dir.path().join("a"), None);
    let tiles = dir.path().join("tiles");
    std::fs::create_dir_all(tiles.join("normals")).expect("mkdir");
    let mut file = b"SMTILE2\0".to_vec();
    file.extend((payload.len() as u64).to_le_bytes());
    file.extend(u64::from(crc32fast::hash(payload)).to_le_bytes());
    file.extend_from_slice(payload);
    let forged = tiles.join("normals/0000000.tile");
    std::fs::write(&forged, file).expect("forge");
    let (resumed, damaged) = normals_of(&dir.path().join("b"), Some(&tiles));
    assert!(resumed == clean, "the forged tile reached the normals");
    assert_eq!(damaged, vec![forged]);
}

/// The other side of the check above: every tile a run saved fits its
/// tile, so a resumed run reuses them all (normals, marching cubes,
/// neighbours) and rejects none.
#[test]
fn a_resumed_run_rejects_none_of_its_own_tiles() {
    let dir = tempfile::tempdir().expect("tmp");
    let input = dir.path().join("in.xyz");
    write_xyz(&input, &utm_points(20_000, 7));
    // The terrain is an open sheet, which `--closed` closes (into a slab),
    // resumed or not.
    for (command, out, extra) in [
        ("reconstruct", "m.ply", &["--closed"][..]),
        ("neighbors", "a.csr", &[][..]),
        ("normals", "n.ply", &["--orient", "sources"][..]),
    ] {
        let out = dir.path().join(out);
        let run = dir.path().join(format!("run-{command}"));
        let args = [
            &[command, s(&input), "-o", s(&out), "--run-dir", s(&run)][..],
            &["--tile-points", "3000", "-q"],
            extra,
        ]
        .concat();
        ok(&args);
        std::fs::remove_file(&out).expect("rm output");
        let _ = std::fs::remove_dir_all(run.join("stages"));
        let o = scanmesh(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success(), "{command}: {err}");
        assert!(!err.contains("damaged tile"), "{command}: {err}");
        assert!(out.is_file());
    }
}

/// The interpolating methods' vertices are the input's points: written
/// with the input's coordinates exactly, not the store's f32 offsets.
#[test]
fn interpolating_meshes_keep_the_inputs_coordinates() {
    let dir = tempfile::tempdir().expect("tmp");
    let pts = utm_points(20_000, 8);
    let xyz = dir.path().join("utm.xyz");
    write_xyz(&xyz, &pts);
    let mut want: Vec<[u64; 3]> = std::fs::read_to_string(&xyz)
        .expect("read")
        .lines()
        .map(|l| {
            let v: Vec<f64> = l.split(' ').map(|t| t.parse().expect("f64")).collect();
            [v[0].to_bits(), v[1].to_bits(), v[2].to_bits()]
        })
        .collect();
    want.sort_unstable();
    for method in ["projection", "delaunay"] {
        let out = dir.path().join(format!("{method}.ply"));
        let args = ["--method", method, "--tile-points", "4000", "-q"];
        ok(&[&["reconstruct", s(&xyz), "-o", s(&out)][..], &args].concat());
        let mut got: Vec<[u64; 3]> = ply_xyz(&out).iter().map(|p| p.map(f64::to_bits)).collect();
        got.sort_unstable();
        assert!(got == want, "{method}: vertices are not the input's points");
    }
}

/// Real aerial LAS/LAZ (las-rs's test data): LAS out holds the input's
/// integers under its scale and offset, PLY out the f64 they make.
#[test]
fn real_las_files_come_out_with_their_own_integers() {
    let dir = tempfile::tempdir().expect("tmp");
    for name in ["autzen.las", "32-1-472-150-76.laz"] {
        let input = Path::new("tests/fixtures/las").join(name);
        let (ints, tf) = las_raw(&input);
        for out in ["n.las", "n.laz"] {
            let out = dir.path().join(out);
            ok(&["normals", s(&input), "-o", s(&out), "-q"]);
            let (got, got_tf) = las_raw(&out);
            assert_eq!(got_tf, tf, "{name}: the LAS transform changed");
            assert!(got == ints, "{name}: integers changed");
        }
        let ply = dir.path().join("k.ply");
        ok(&["curvature", s(&input), "-o", s(&ply), "-q"]);
        let decoded: Vec<[f64; 3]> = ints
            .iter()
            .map(|i| [0, 1, 2].map(|a| tf[a] * f64::from(i[a]) + tf[3 + a]))
            .collect();
        assert!(ply_xyz(&ply) == decoded, "{name}: curvature moved points");
    }
}
