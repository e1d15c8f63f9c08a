//! `scanmesh outliers`: the scores against a brute-force oracle, the thrown
//! points of a scattered sphere found, 64+ tiles on two threads equal to one
//! tile on one thread bit for bit (scores, threshold, flags), and the
//! command on real scans through every point format of the output table,
//! each output's rows and flags the same.

mod common;

use common::with_store;
use glam::DVec3;
use scanmesh::io::{open_reader, InvalidPolicy, PointChunk};
use scanmesh::outliers::{
    compute_outliers, OutlierParams, OutlierReport, FEWER_THAN_K, OUTLIER, OUTLIER_FLAGS,
    OUTLIER_SCORE,
};
use scanmesh::pipeline::{NoProgress, RunOptions};
use scanmesh::store::PointStore;
use scanmesh::synth::{generate, mean_spacing_hint, Rng, Shape};
use std::path::Path;
use std::process::Command;

/// A sphere of `n` points, every `every`-th thrown off it along its
/// normal by 10 to 25 spacings (stray returns in front of the surface).
fn scattered_sphere(n: usize, every: usize, seed: u64) -> Vec<DVec3> {
    let sphere = Shape::Sphere {
        centre: DVec3::new(1.0, 2.0, 3.0),
        radius: 1.0,
    };
    let scan = generate(&sphere, n, 0.0, seed).expect("scan");
    let spacing = mean_spacing_hint(&sphere, n).expect("spacing");
    let mut rng = Rng::new(seed + 7);
    (0..n)
        .map(|i| match i % every == every - 1 {
            true => scan.points[i] + scan.normals[i] * spacing * rng.range(10.0, 25.0),
            false => scan.points[i],
        })
        .collect()
}

/// Scores and flags by input id.
fn by_id(store: &PointStore) -> (Vec<f32>, Vec<u8>) {
    let n = store.len() as usize;
    let (mut scores, mut flags) = (vec![f32::NAN; n], vec![0u8; n]);
    let s = store.column(&OUTLIER_SCORE).expect("scores");
    let f = store.column(&OUTLIER_FLAGS).expect("flags");
    let (mut ids, mut sv, mut fv) = (Vec::new(), Vec::new(), Vec::new());
    for t in store.tiles() {
        store.read_indices(t.start, t.count, &mut ids).unwrap();
        s.read_f32(t.start, t.count, &mut sv).unwrap();
        f.read_u8(t.start, t.count, &mut fv).unwrap();
        for (k, &id) in ids.iter().enumerate() {
            scores[id as usize] = sv[k];
            flags[id as usize] = fv[k];
        }
    }
    (scores, flags)
}

struct Run {
    report: OutlierReport,
    scores: Vec<f32>,
    flags: Vec<u8>,
}

fn run(points: &[DVec3], tile_points: u64, threads: usize, params: OutlierParams) -> Run {
    with_store(points, tile_points, threads, |store, _| {
        let opts = RunOptions::new(threads);
        let report = compute_outliers(store, &params, opts, &NoProgress).expect("outliers");
        let (scores, flags) = by_id(store);
        Run {
            report,
            scores,
            flags,
        }
    })
}

#[test]
fn finds_the_thrown_points_and_tiles_change_nothing() {
    let params = OutlierParams::default();
    for seed in [1, 2] {
        let (n, every) = (20_000, 100);
        let points = scattered_sphere(n, every, seed);
        let whole = run(&points, u64::MAX, 1, params);
        let tiled = run(&points, 250, 2, params);
        assert_eq!(whole.report.run.tiles, 1);
        assert!(tiled.report.run.tiles >= 64, "{}", tiled.report.run.tiles);
        let bits = |r: &Run| r.scores.iter().map(|s| s.to_bits()).collect::<Vec<_>>();
        assert!(bits(&whole) == bits(&tiled), "seed {seed}: scores differ");
        assert_eq!(whole.flags, tiled.flags, "seed {seed}");
        assert_eq!(
            whole.report.threshold.to_bits(),
            tiled.report.threshold.to_bits()
        );
        // Against brute force over the f64 points (the store holds f32).
        let ids: Vec<u64> = (0..n as u64).collect();
        for i in (0..n).step_by(37) {
            let nn = scanmesh::spatial::brute_knn(&points, &ids, points[i], 20, Some(i as u32));
            let mean = nn.iter().map(|m| m.dist2.sqrt()).sum::<f64>() / 20.0;
            let got = f64::from(whole.scores[i]);
            assert!(
                (got - mean).abs() <= 1e-5 * mean,
                "point {i}: {got} vs {mean}"
            );
        }
        // The rule over the oracle's scores: the sample standard deviation.
        let s: Vec<f64> = whole.scores.iter().map(|&v| f64::from(v)).collect();
        let mean = s.iter().sum::<f64>() / n as f64;
        let var = s.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
        let threshold = mean + 2.0 * var.sqrt();
        assert!((whole.report.threshold - threshold).abs() <= 1e-9 * threshold);
        let want: Vec<u8> = s.iter().map(|&v| u8::from(v > threshold)).collect();
        assert_eq!(whole.flags, want, "seed {seed}: flags against the rule");
        // Every thrown point is found; few surface points are taken for one.
        let thrown = |i: usize| i % every == every - 1;
        let found = (0..n).filter(|&i| thrown(i) && whole.flags[i] == OUTLIER);
        assert_eq!(found.count(), n / every, "seed {seed}: thrown points found");
        let taken = (0..n).filter(|&i| !thrown(i) && whole.flags[i] == OUTLIER);
        assert!(taken.count() < n / 200, "seed {seed}: surface points taken");
    }
}

#[test]
fn a_cloud_smaller_than_k_is_not_judged() {
    let points: Vec<DVec3> = (0..8).map(|i| DVec3::new(i as f64, 0.5, 0.25)).collect();
    let r = run(&points, u64::MAX, 1, OutlierParams::default());
    assert_eq!(r.report.not_judged, 8);
    assert!(r.flags.iter().all(|&f| f == FEWER_THAN_K));
    // Each point's score is over the 7 others it has.
    let want = (1..8).map(f64::from).sum::<f64>() / 7.0;
    assert!((f64::from(r.scores[0]) - want).abs() < 1e-6);
}

#[test]
fn bad_parameters_are_refused() {
    for (k, ratio) in [(0, 2.0), (1001, 2.0), (20, 0.0), (20, f64::NAN), (20, -1.0)] {
        let e = OutlierParams { k, ratio }.validate().expect_err("refused");
        assert!(e.to_string().contains("must be"), "{e}");
    }
}

fn scanmesh(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_scanmesh"))
        .args(args)
        .output()
        .expect("scanmesh")
}

fn read_all(path: &Path) -> PointChunk {
    let mut r = open_reader(path, InvalidPolicy::Reject).expect("read");
    let mut chunk = PointChunk::default();
    r.read_chunk(&mut chunk, usize::MAX).expect("chunk");
    chunk
}

/// The output's flags: the last byte of each PLY record.
fn ply_flags(path: &Path, record: usize) -> Vec<u8> {
    let bytes = std::fs::read(path).expect("ply");
    let n = read_all(path).len();
    let body = &bytes[bytes.len() - n * record..];
    body.chunks_exact(record).map(|r| r[record - 1]).collect()
}

/// Real scans of four kinds through every format the table gives the
/// score: the same points in the same order in each (read back by the
/// library's readers), the PLY's flags counted as the summary says, and
/// XYZ and E57 refused naming the formats that hold the score.
#[test]
fn real_scans_through_every_format() {
    let fixtures = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures");
    let dir = tempfile::tempdir().expect("tmp");
    for input in [
        "las/autzen_trim_cut.laz",
        "las/warsaw_small.las",
        "e57/kinect_two_scans.e57",
        "pcd/organised_milk.pcd",
    ] {
        let input = fixtures.join(input);
        let s = input.to_str().unwrap();
        let want = read_all(&input).xyz.len();
        let ply = dir.path().join("o.ply");
        let out = scanmesh(&[
            "outliers",
            s,
            "-o",
            ply.to_str().unwrap(),
            "--tile-points",
            "4000",
        ]);
        let said = String::from_utf8_lossy(&out.stdout).to_string();
        assert!(
            out.status.success(),
            "{s}: {said}{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let flags = ply_flags(&ply, 24 + 4 + 1);
        let outliers = flags.iter().filter(|&&f| f == OUTLIER).count();
        assert!(
            said.contains(&format!("outliers: {outliers} of {} points", flags.len())),
            "{s}: {said}"
        );
        assert!(outliers > 0 && outliers < flags.len() / 10, "{s}: {said}");
        let xyz = read_all(&ply).xyz;
        for ext in ["pcd", "las", "laz"] {
            let other = dir.path().join(format!("o.{ext}"));
            let out = scanmesh(&["outliers", s, "-o", other.to_str().unwrap(), "-q"]);
            assert!(out.status.success(), "{s} -> {ext}");
            let back = read_all(&other).xyz;
            assert_eq!(back.len(), xyz.len(), "{s} -> {ext}");
            let far = back.iter().zip(&xyz).map(|(a, b)| a.distance(*b));
            // LAS quantises a non-LAS input's coordinates.
            assert!(far.fold(0.0, f64::max) < 1e-3, "{s} -> {ext}: points moved");
        }
        assert!(xyz.len() <= want, "{s}");
        for ext in ["xyz", "e57"] {
            let other = dir.path().join(format!("o.{ext}"));
            let out = scanmesh(&["outliers", s, "-o", other.to_str().unwrap(), "-q"]);
            let e = String::from_utf8_lossy(&out.stderr);
            assert!(
                !out.status.success() && e.contains("write .ply, .pcd, .las or .laz"),
                "{e}"
            );
            assert!(!other.exists());
        }
    }
}

/// `--drop` writes the rows the rule keeps: every row of the full output
/// whose flag is not [`OUTLIER`], in the same order, in every format; with
/// `--classes` and `--unselected keep`, the unselected rows stay (flag 128).
#[test]
fn drop_writes_the_kept_rows_in_order() {
    let fixtures = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures");
    let dir = tempfile::tempdir().expect("tmp");
    let run = |input: &Path, name: &str, extra: &[&str]| {
        let out = dir.path().join(name);
        let args = [
            &[
                "outliers",
                input.to_str().unwrap(),
                "-o",
                out.to_str().unwrap(),
                "-q",
            ][..],
            extra,
        ]
        .concat();
        let o = scanmesh(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        out
    };
    for (input, select) in [
        ("las/autzen_trim_cut.laz", &[][..]),
        ("e57/kinect_two_scans.e57", &[]),
        (
            "las/32-1-472-150-76.laz",
            &["--classes", "2", "--unselected", "keep"],
        ),
    ] {
        let input = fixtures.join(input);
        let all = run(&input, "all.ply", select);
        let flags = ply_flags(&all, 24 + 4 + 1);
        let xyz = read_all(&all).xyz;
        let kept: Vec<DVec3> = (0..xyz.len())
            .filter(|&i| flags[i] != OUTLIER)
            .map(|i| xyz[i])
            .collect();
        assert!(kept.len() < xyz.len(), "{input:?}: nothing to drop");
        let dropped = run(&input, "kept.ply", &[select, &["--drop"]].concat());
        assert!(read_all(&dropped).xyz == kept, "{input:?}");
        let left = ply_flags(&dropped, 24 + 4 + 1);
        assert!(left.iter().all(|&f| f != OUTLIER), "{input:?}");
        if !select.is_empty() {
            assert!(left.contains(&128), "{input:?}: unselected rows dropped");
        }
        for ext in ["las", "pcd"] {
            let other = run(
                &input,
                &format!("kept.{ext}"),
                &[select, &["--drop"]].concat(),
            );
            let back = read_all(&other).xyz;
            assert_eq!(back.len(), kept.len(), "{input:?} {ext}");
        }
    }
}
