//! Neighbourhoods end to end (issue 4): tiled == untiled byte for byte in
//! both modes, 1 thread == 2 threads, kNN against a brute-force oracle,
//! topological lists against an untiled run of paper 3 over all points and
//! containing the kNN lists, text == binary, no output unless the run
//! succeeds, and paper 3's iteration statistics on the dragon.

mod common;

use common::{store_of, with_store};
use glam::DVec3;
use scanmesh::neighbours::{
    compute_neighbours, read_csr, Csr, NeighbourParams, Neighbourhood, NeighboursError,
    NeighboursKernel, NeighboursReport, OutputFormat, OutputOptions,
};
use scanmesh::pipeline::{run_tiles, NoProgress, RunOptions};
use scanmesh::spatial::rtree::RTreeIndex;
use scanmesh::spatial::topological::{all_topological, TopoParams};
use scanmesh::store::PointStore;
use scanmesh::synth::{generate, Rng, Shape};
use std::path::Path;

struct Run {
    report: NeighboursReport,
    bytes: Vec<u8>,
}

/// Builds a store with tiles of at most `tile_points` and computes the
/// neighbourhoods with `threads` workers (and a rayon pool of that size).
fn run(
    points: &[DVec3],
    tile_points: u64,
    threads: usize,
    params: &NeighbourParams,
    format: OutputFormat,
    window_points: u64,
) -> Run {
    with_store(points, tile_points, threads, |store, dir| {
        let out = dir.join("out.nbr");
        let opts = OutputOptions {
            format,
            window_points,
        };
        let report = compute_neighbours(
            store,
            params,
            &out,
            &opts,
            RunOptions::new(threads),
            &NoProgress,
        )
        .expect("neighbours");
        Run {
            report,
            bytes: std::fs::read(&out).expect("read output"),
        }
    })
}

fn csr_of(bytes: &[u8]) -> Csr {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("x.nbr");
    std::fs::write(&path, bytes).expect("write");
    read_csr(&path).expect("valid CSR")
}

/// The store's coordinates in input order: what every kernel sees.
fn stored_points(store: &PointStore) -> Vec<DVec3> {
    let (mut pts, mut ids) = (Vec::new(), Vec::new());
    store.read_points(0, store.len(), &mut pts).expect("points");
    store.read_indices(0, store.len(), &mut ids).expect("ids");
    let mut out = vec![DVec3::ZERO; pts.len()];
    for (p, id) in pts.iter().zip(&ids) {
        out[*id as usize] = *p;
    }
    out
}

fn stored_points_of(points: &[DVec3]) -> Vec<DVec3> {
    let dir = tempfile::tempdir().expect("tempdir");
    stored_points(&store_of(points, &dir.path().join("s"), 1 << 20))
}

/// Exact kNN by sorting every other point by (squared distance, id).
fn brute_knn(points: &[DVec3], i: usize, k: usize) -> Vec<u64> {
    let mut all: Vec<(f64, u64)> = (0..points.len())
        .filter(|&j| j != i)
        .map(|j| ((points[j] - points[i]).length_squared(), j as u64))
        .collect();
    all.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    all.truncate(k);
    all.into_iter().map(|(_, j)| j).collect()
}

/// A noisy terrain scan: a density step, buildings, ground.
fn terrain(n: usize, seed: u64) -> Vec<DVec3> {
    generate(&Shape::terrain(), n, 0.02, seed)
        .expect("generate")
        .points
}

/// An integer lattice in shuffled input order: every distance ties often.
fn shuffled_lattice(side: usize, seed: u64) -> Vec<DVec3> {
    let mut pts: Vec<DVec3> = (0..side * side)
        .map(|i| DVec3::new((i % side) as f64, (i / side) as f64, ((i * 7) % 3) as f64))
        .collect();
    let mut rng = Rng::new(seed);
    for i in (1..pts.len()).rev() {
        pts.swap(i, (rng.next_u64() % (i as u64 + 1)) as usize);
    }
    pts
}

#[test]
fn tiled_equals_untiled_byte_for_byte_in_both_modes() {
    let points = terrain(6000, 5);
    for params in [
        NeighbourParams::topological(15, 10),
        NeighbourParams::knn(15),
    ] {
        let whole = run(&points, u64::MAX, 2, &params, OutputFormat::Csr, 1 << 20);
        let tiled = run(&points, 80, 2, &params, OutputFormat::Csr, 997);
        let mode = params.mode_name();
        println!(
            "{mode}: {} tiles, {} reloaded, largest margin {:.3}",
            tiled.report.tiles, tiled.report.run.retries, tiled.report.run.largest_margin
        );
        assert_eq!(whole.report.tiles, 1);
        assert!(
            tiled.report.tiles >= 64,
            "{mode}: only {} tiles",
            tiled.report.tiles
        );
        assert!(whole.bytes == tiled.bytes, "{mode}: tiled output differs");
        assert_eq!(
            whole.report.stats, tiled.report.stats,
            "{mode}: statistics differ"
        );
    }
}

#[test]
fn one_thread_equals_two_threads() {
    let points = generate(&Shape::torus(1.0, 0.3), 5000, 0.002, 9)
        .expect("generate")
        .points;
    for params in [
        NeighbourParams::topological(12, 10),
        NeighbourParams::knn(10),
    ] {
        let one = run(&points, 150, 1, &params, OutputFormat::Csr, 1000);
        let two = run(&points, 150, 2, &params, OutputFormat::Csr, 1000);
        assert!(
            one.bytes == two.bytes,
            "{}: outputs differ",
            params.mode_name()
        );
    }
}

#[test]
fn knn_equals_brute_force_with_ties() {
    let sphere = generate(&Shape::unit_sphere(), 1500, 0.01, 21)
        .expect("generate")
        .points;
    for (name, points, seed) in [
        ("sphere", sphere, 21u64),
        ("lattice", shuffled_lattice(36, 4), 4),
    ] {
        let stored = stored_points_of(&points);
        for k in [1, 8, 15] {
            let params = NeighbourParams::knn(k);
            let csr = csr_of(&run(&points, 40, 2, &params, OutputFormat::Csr, 333).bytes);
            assert_eq!(csr.len(), points.len());
            for i in 0..points.len() {
                assert_eq!(
                    csr.list(i),
                    brute_knn(&stored, i, k).as_slice(),
                    "cloud {name} seed {seed} k {k} point {i}"
                );
            }
        }
    }
}

#[test]
fn topological_equals_untiled_paper_3_and_contains_knn() {
    // A uniform sample: paper 3's T contains the kNN (T starts from them).
    let points = generate(&Shape::hole_plane(2.0, 0.4), 3000, 0.0, 13)
        .expect("generate")
        .points;
    let stored = stored_points_of(&points);
    let ids: Vec<u64> = (0..stored.len() as u64).collect();
    let index = RTreeIndex::new(&stored, &ids).expect("index");
    let oracle = all_topological(&index, &stored, &ids, &TopoParams::default()).expect("topo");
    let topo = run(
        &points,
        40,
        2,
        &NeighbourParams::topological(15, 10),
        OutputFormat::Csr,
        500,
    );
    let knn = run(
        &points,
        40,
        2,
        &NeighbourParams::knn(15),
        OutputFormat::Csr,
        500,
    );
    let (topo, knn) = (csr_of(&topo.bytes), csr_of(&knn.bytes));
    let mut extra = 0;
    assert_eq!(oracle.len(), points.len());
    for (i, o) in oracle.iter().enumerate() {
        let want: Vec<u64> = o.neighbours.iter().map(|n| n.index as u64).collect();
        assert_eq!(topo.list(i), want.as_slice(), "seed 13 point {i}");
        for id in knn.list(i) {
            assert!(
                topo.list(i).contains(id),
                "seed 13 point {i}: kNN {id} not in T"
            );
        }
        extra += topo.list(i).len() - knn.list(i).len();
    }
    println!(
        "topological adds {extra} neighbours over kNN on {} points",
        points.len()
    );
    assert!(extra > 0, "the reverse shift never added a point");
}

/// The kernel alone with a first margin far too small: every neighbourhood
/// must still equal the oracle's, through run-time margin checks and reloads.
#[test]
fn kernel_widens_a_small_margin_until_lists_are_exact() {
    let points = terrain(2000, 23);
    let stored = stored_points_of(&points);
    let ids: Vec<u64> = (0..stored.len() as u64).collect();
    let index = RTreeIndex::new(&stored, &ids).expect("index");
    let topo = TopoParams {
        k: 15,
        max_iterations: 10,
    };
    let oracle = all_topological(&index, &stored, &ids, &topo).expect("topo");
    let dir = tempfile::tempdir().expect("tempdir");
    let store = store_of(&points, &dir.path().join("s"), 60);
    for params in [
        NeighbourParams::topological(15, 10),
        NeighbourParams::knn(15),
    ] {
        let kernel = NeighboursKernel {
            params,
            initial_margin: 1e-3,
        };
        let mut lists = vec![Vec::new(); points.len()];
        let stats = run_tiles(&store, &kernel, RunOptions::new(2), &NoProgress, |_, t| {
            for (i, id) in t.ids.iter().enumerate() {
                let range = t.offsets[i] as usize..t.offsets[i + 1] as usize;
                lists[*id as usize] = t.neighbours[range].to_vec();
            }
            Ok(())
        })
        .expect("run");
        let mode = params.mode_name();
        println!("{mode}: {} tiles, {} reloads", stats.tiles, stats.retries);
        assert!(stats.retries >= stats.tiles, "{mode}: margin never widened");
        for (i, got) in lists.iter().enumerate() {
            let want: Vec<u64> = match params.neighbourhood {
                Neighbourhood::Topological(_) => oracle[i]
                    .neighbours
                    .iter()
                    .map(|n| n.index as u64)
                    .collect(),
                Neighbourhood::Knn { k } => brute_knn(&stored, i, k),
            };
            assert_eq!(got, &want, "{mode} seed 23 point {i}");
        }
    }
}

fn parse_text(text: &str) -> Vec<Vec<u64>> {
    text.lines()
        .enumerate()
        .map(|(line, l)| {
            let mut ids = l.split(' ').map(|t| t.parse::<u64>().expect("an id"));
            assert_eq!(
                ids.next(),
                Some(line as u64),
                "line {line} starts with its id"
            );
            ids.collect()
        })
        .collect()
}

#[test]
fn text_and_binary_agree() {
    let points = terrain(2500, 17);
    for params in [
        NeighbourParams::topological(15, 10),
        NeighbourParams::knn(6),
    ] {
        let bin = run(&points, 100, 2, &params, OutputFormat::Csr, 300);
        let txt = run(&points, 100, 2, &params, OutputFormat::Text, 700);
        let csr = csr_of(&bin.bytes);
        let lines = parse_text(std::str::from_utf8(&txt.bytes).expect("utf8"));
        assert!(txt.bytes.ends_with(b"\n"));
        assert_eq!(lines.len(), csr.len());
        for (i, l) in lines.iter().enumerate() {
            assert_eq!(
                l.as_slice(),
                csr.list(i),
                "{} point {i}",
                params.mode_name()
            );
        }
        assert_eq!(bin.report.neighbours, csr.neighbours.len() as u64);
    }
}

fn names_in(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .expect("list")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn output_is_left_only_on_success() {
    let points = terrain(1500, 3);
    let dir = tempfile::tempdir().expect("tempdir");
    let store_dir = dir.path().join("store");
    let mut store = store_of(&points, &store_dir, 100);
    let opts = OutputOptions {
        format: OutputFormat::Csr,
        window_points: 256,
    };
    let params = NeighbourParams::default();
    let go = |store: &mut PointStore, out: &Path, params: &NeighbourParams| {
        compute_neighbours(store, params, out, &opts, RunOptions::new(2), &NoProgress)
    };
    let store_files = names_in(&store_dir);
    // Unwritable: the directory does not exist.
    let missing = dir.path().join("no/such/dir/out.nbr");
    assert!(matches!(
        go(&mut store, &missing, &params),
        Err(NeighboursError::Io(_))
    ));
    // Fails at the very end: the final name is a non-empty directory.
    let blocked = dir.path().join("blocked");
    std::fs::create_dir(&blocked).expect("mkdir");
    std::fs::write(blocked.join("keep"), b"x").expect("write");
    let outs = dir.path().join("outs");
    std::fs::create_dir(&outs).expect("mkdir");
    let before = names_in(dir.path());
    assert!(go(&mut store, &blocked, &params).is_err());
    assert_eq!(names_in(dir.path()), before, "a partial file was left");
    assert_eq!(names_in(&blocked), vec!["keep".to_string()]);
    // Bad parameters: nothing is created.
    let bad = outs.join("bad.nbr");
    assert!(matches!(
        go(&mut store, &bad, &NeighbourParams::knn(0)),
        Err(NeighboursError::BadParams { .. })
    ));
    assert!(names_in(&outs).is_empty());
    // Success: exactly the output, and the store holds no scratch files.
    let good = outs.join("good.nbr");
    go(&mut store, &good, &params).expect("success");
    assert_eq!(names_in(&outs), vec!["good.nbr".to_string()]);
    assert_eq!(
        csr_of(&std::fs::read(&good).expect("read")).len(),
        points.len()
    );
    let mut after = names_in(&store_dir);
    after.retain(|n| !n.starts_with(".neighbours"));
    assert_eq!(after, store_files, "store files changed");
    assert!(names_in(&store_dir)
        .iter()
        .all(|n| !n.starts_with(".neighbours")));
}

#[test]
fn dragon_iterations_match_paper_3() {
    let (scan, _, _) = scanmesh::demo::dragon_scan(20_000, 0.1, 8).expect("dragon");
    let k = 15;
    let params = NeighbourParams::topological(k, 10);
    let out = run(&scan.points, 2000, 2, &params, OutputFormat::Csr, 1 << 20);
    let st = &out.report.stats;
    let median = st.median_iterations().expect("median");
    let within = st.fraction_sized(k, 3 * k).expect("fraction");
    println!(
        "dragon 20k seed 8, k {k}: iterations histogram {:?} (median {median}, {} hit the cap); \
         |T| min/median/mean/max {:?}/{:?}/{:.2}/{:?}; {:.2} % in [k, 3k]; {} tiles, {} reloaded",
        st.iteration_histogram(),
        st.hit_cap(),
        st.min_size(),
        st.median_size(),
        st.mean_size().unwrap_or(f64::NAN),
        st.max_size(),
        100.0 * within,
        out.report.tiles,
        out.report.run.retries
    );
    assert!(median <= 4, "median iterations {median}");
    assert!(
        within >= 0.95,
        "only {:.2} % with |T| in [k, 3k]",
        100.0 * within
    );
    assert_eq!(st.min_size(), Some(k));
}

#[test]
fn cli_writes_text_binary_and_summary() {
    let dir = tempfile::tempdir().expect("tempdir");
    let input = dir.path().join("in.xyz");
    let body: String = terrain(1200, 31)
        .iter()
        .map(|p| format!("{} {} {}\n", p.x, p.y, p.z))
        .collect();
    std::fs::write(&input, body).expect("write");
    let cli = |args: &[&str]| {
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_scanmesh"))
            .arg("neighbors")
            .arg(&input)
            .args(["--tile-points", "100", "-q", "--k", "10"])
            .args(args)
            .output()
            .expect("run scanmesh");
        let err = String::from_utf8_lossy(&o.stderr).into_owned();
        assert!(o.status.success(), "{args:?}: {err}");
        String::from_utf8_lossy(&o.stdout).into_owned()
    };
    let (bin, txt, json) = (
        dir.path().join("n.nbr"),
        dir.path().join("n.txt"),
        dir.path().join("s.json"),
    );
    let line = cli(&[
        "-o",
        bin.to_str().expect("path"),
        "--summary",
        json.to_str().expect("path"),
    ]);
    println!("{line}");
    assert!(line.starts_with("neighbors: 1200 points"), "{line}");
    cli(&["-o", txt.to_str().expect("path"), "--format", "txt"]);
    let csr = read_csr(&bin).expect("csr");
    let lines = parse_text(&std::fs::read_to_string(&txt).expect("text"));
    assert_eq!(lines.len(), 1200);
    for (i, l) in lines.iter().enumerate() {
        assert_eq!(l.as_slice(), csr.list(i), "point {i}");
    }
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).expect("json")).expect("parse");
    assert_eq!(s["mode"], "topological");
    assert_eq!(s["k"], 10);
    assert_eq!(s["points"], 1200);
    assert_eq!(s["neighbours"], csr.neighbours.len() as u64);
    let sizes: Vec<usize> = (0..csr.len()).map(|i| csr.list(i).len()).collect();
    assert_eq!(s["size"]["min"], *sizes.iter().min().expect("min") as u64);
    assert_eq!(s["size"]["max"], *sizes.iter().max().expect("max") as u64);
    let hist = s["iterations"]["histogram"].as_array().expect("histogram");
    assert_eq!(
        hist.iter().map(|c| c.as_u64().unwrap_or(0)).sum::<u64>(),
        1200
    );
    let knn_line = cli(&["-o", bin.to_str().expect("path"), "--neighbours", "knn"]);
    assert!(knn_line.contains("knn k 10"), "{knn_line}");
    let knn = read_csr(&bin).expect("csr");
    assert!((0..knn.len()).all(|i| knn.list(i).len() == 10));
    let left: Vec<String> = names_in(dir.path());
    assert_eq!(
        left,
        ["in.xyz", "n.nbr", "n.txt", "s.json"],
        "scratch left behind"
    );
}

#[test]
fn a_k_outside_its_range_is_refused() {
    for bad in [
        NeighbourParams::knn(0),
        NeighbourParams::topological(0, 4),
        NeighbourParams::knn(1 << 20),
    ] {
        assert!(
            matches!(bad.validate(), Err(NeighboursError::BadParams { .. })),
            "{bad:?} accepted"
        );
    }
    assert!(NeighbourParams::knn(8).validate().is_ok());
}
