//! A tile kernel of your own, outside the library: statistical outlier
//! scores, run out of core over a tiled store by the library's pipeline.
//!
//! A point's score is its mean distance to its `k` nearest neighbours; it
//! is an outlier when the score exceeds the mean score by more than `ratio`
//! standard deviations (the rule of Open3D's `remove_statistical_outlier`
//! and PCL's `StatisticalOutlierRemoval`; k = 20, ratio = 2 are Open3D's
//! usual values). Nothing in the library knows of this kernel: it is a type
//! that implements `TileKernel`, and the tiles, their margins, the reload
//! of a tile whose margin proves short, the worker threads and the tile
//! order are the pipeline's. Exact whatever the tiling: a score is taken
//! only when its neighbours' ball lies inside the loaded region.
//!
//! `cargo run --release --example outliers -- scan.ply [k] [ratio]`;
//! without arguments, 50,000 points of the embedded dragon with 1 % of
//! them thrown off the surface.

use glam::DVec3;
use scanmesh::pipeline::{run_tiles, KernelError, PipelineError, TileKernel, TilePoints};
use scanmesh::spatial::{build_index, KnnBackend};
use scanmesh::store::TileTarget;
use scanmesh::synth::{Rng, Scan};
use scanmesh::{build_store, open_reader, open_stream_reader, BuildOptions, PointReader};
use scanmesh::{NoProgress, PointStore, ReadOptions, RunOptions};
use std::path::Path;

type Error = Box<dyn std::error::Error>;

/// The kernel: per core point, (input id, mean distance to the k nearest).
struct OutlierScores {
    k: usize,
    /// First margin to load; the pipeline widens it when a tile asks.
    margin: f64,
}

impl TileKernel for OutlierScores {
    type Output = Vec<(u64, f64)>;

    fn name(&self) -> &str {
        "outlier scores"
    }

    fn margin(&self) -> f64 {
        self.margin
    }

    fn run(&self, tile: &TilePoints) -> Result<Self::Output, KernelError> {
        let index =
            build_index(KnnBackend::Grid, &tile.points, &tile.ids).map_err(KernelError::failed)?;
        let (mut found, mut short) = (Vec::new(), 0.0f64);
        let mut scores = Vec::with_capacity(tile.n_core);
        for (i, &p) in tile.core_points().iter().enumerate() {
            index.knn(p, self.k, Some(i as u32), &mut found);
            // Fewer than k loaded: how far the k-th lies is unknown.
            let reach = match found.get(self.k - 1) {
                Some(n) => n.dist2.sqrt(),
                None => f64::INFINITY,
            };
            short = short.max(tile.shortfall(p, reach));
            let sum: f64 = found.iter().map(|n| n.dist2.sqrt()).sum();
            scores.push((tile.ids[i], sum / found.len().max(1) as f64));
        }
        // The library's one margin rule: reload wider, or accept.
        KernelError::unless_short(short, tile.margin)?;
        Ok(scores)
    }
}

/// Every point's score by input id, and the outliers' ids.
struct Outliers {
    scores: Vec<f64>,
    threshold: f64,
    ids: Vec<u64>,
    tiles: usize,
}

/// Runs the kernel over `store`. The seam policy here is the simplest
/// there is (each core point's score is final); a command over huge scans
/// would write the scores to a store column instead of a `Vec`.
fn find_outliers(
    store: &PointStore,
    k: usize,
    ratio: f64,
    threads: usize,
) -> Result<Outliers, Error> {
    if k == 0 || !(ratio.is_finite() && ratio > 0.0) {
        return Err(format!("k must be at least 1 and ratio positive (got {k}, {ratio})").into());
    }
    let spacing = store.manifest().spacing.unwrap_or(0.0);
    let kernel = OutlierScores {
        k,
        margin: (4.0 * spacing).max(1e-9),
    };
    let mut scores = vec![f64::NAN; store.len() as usize];
    run_tiles(
        store,
        &kernel,
        RunOptions::new(threads),
        &NoProgress,
        |_, tile| {
            for (id, score) in tile {
                scores[id as usize] = score;
            }
            Ok::<(), PipelineError>(())
        },
    )?;
    // Summed in input order, so the threshold is the same for any tiling.
    let n = scores.len().max(1) as f64;
    let mean = scores.iter().sum::<f64>() / n;
    let var = scores.iter().map(|s| (s - mean).powi(2)).sum::<f64>() / n;
    let threshold = mean + ratio * var.sqrt();
    let ids = (0..scores.len() as u64)
        .filter(|&i| scores[i as usize] > threshold)
        .collect();
    let tiles = store.tiles().len();
    Ok(Outliers {
        scores,
        threshold,
        ids,
        tiles,
    })
}

fn main() -> Result<(), Error> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut reader = match args.first() {
        Some(input) => open_reader(input.as_ref(), ReadOptions::default())?,
        None => stream(&scattered_dragon(50_000, 100)?)?,
    };
    let k = args.get(1).map_or(Ok(20), |s| s.parse())?;
    let ratio = args.get(2).map_or(Ok(2.0), |s| s.parse())?;
    let work = tempfile::tempdir()?;
    // Tiles of at most 2^18 points, so a million-point scan runs tiled.
    let options = BuildOptions {
        tiles: TileTarget::Points(1 << 18),
        ..BuildOptions::default()
    };
    let store = build_store(
        &mut *reader,
        &work.path().join("store"),
        &options,
        &NoProgress,
    )?;
    let found = find_outliers(&store, k, ratio, 2)?;
    println!(
        "{} of {} points are outliers (mean distance to the {k} nearest above {:.4e}); {} tiles",
        found.ids.len(),
        found.scores.len(),
        found.threshold,
        found.tiles
    );
    Ok(())
}

/// `n` noisy dragon points, every `every`-th thrown off (`scattered`).
fn scattered_dragon(n: usize, every: usize) -> Result<Vec<[f64; 3]>, Error> {
    let (scan, _, spacing) = scanmesh::demo::dragon_scan(n, 0.1, 1)?;
    Ok(scattered(&scan, spacing, every))
}

/// The scan's points, every `every`-th of them (spread over the surface:
/// the sample's order follows it) moved off the surface along its normal
/// by 10 to 25 `spacing`s (stray returns in front of it).
fn scattered(scan: &Scan, spacing: f64, every: usize) -> Vec<[f64; 3]> {
    let mut rng = Rng::new(7);
    let mut thrown = |i: usize, p: DVec3| p + scan.normals[i] * spacing * rng.range(10.0, 25.0);
    (0..scan.len())
        .map(|i| match i % every == every - 1 {
            true => thrown(i, scan.points[i]).to_array(),
            false => scan.points[i].to_array(),
        })
        .collect()
}

/// Points as an in-memory XYZ stream.
fn stream(points: &[[f64; 3]]) -> Result<Box<dyn PointReader>, Error> {
    let text: String = points
        .iter()
        .map(|p| format!("{} {} {}\n", p[0], p[1], p[2]))
        .collect();
    Ok(open_stream_reader(
        Path::new("points.xyz"),
        std::io::Cursor::new(text),
        ReadOptions::default(),
    )?)
}

/// `cargo test` runs the kernel on the scattered dragon: it finds the
/// thrown points, and 64+ tiles on two threads give one tile's scores on
/// one thread, bit for bit.
#[test]
fn finds_the_thrown_points_and_tiles_change_nothing() {
    use scanmesh::synth::{generate, mean_spacing_hint, Shape};
    // A sphere: a point thrown outward lands near no other part of it
    // (on the dragon some land beside a leg or a horn, and are no outliers).
    let (n, every) = (20_000, 100);
    let sphere = Shape::Sphere {
        centre: DVec3::new(1.0, 2.0, 3.0),
        radius: 1.0,
    };
    let scan = generate(&sphere, n, 0.0, 7).unwrap();
    let spacing = mean_spacing_hint(&sphere, n).unwrap();
    let points = scattered(&scan, spacing, every);
    let work = tempfile::tempdir().unwrap();
    let store_with = |name: &str, tile_points: u64| {
        let options = BuildOptions {
            tiles: TileTarget::Points(tile_points),
            ..BuildOptions::default()
        };
        let mut reader = stream(&points).unwrap();
        build_store(&mut *reader, &work.path().join(name), &options, &NoProgress).unwrap()
    };
    let whole = find_outliers(&store_with("one", u64::MAX), 20, 2.0, 1).unwrap();
    let tiled = find_outliers(&store_with("many", 250), 20, 2.0, 2).unwrap();
    assert_eq!(whole.tiles, 1);
    assert!(tiled.tiles >= 64, "{} tiles", tiled.tiles);
    let bits = |o: &Outliers| o.scores.iter().map(|s| s.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&whole), bits(&tiled));
    assert_eq!(whole.ids, tiled.ids);
    // Against brute force (over the f64 input; the store holds f32).
    let pts: Vec<DVec3> = points.iter().map(|p| DVec3::from_array(*p)).collect();
    let ids: Vec<u64> = (0..n as u64).collect();
    for i in (0..n).step_by(37) {
        let nn = scanmesh::spatial::brute_knn(&pts, &ids, pts[i], 20, Some(i as u32));
        let mean = nn.iter().map(|m| m.dist2.sqrt()).sum::<f64>() / 20.0;
        assert!(
            (whole.scores[i] - mean).abs() <= 1e-5 * mean,
            "point {i}: {} vs {mean}",
            whole.scores[i]
        );
    }
    // Every thrown point is found; few surface points are taken for one.
    let thrown = |i: &&u64| **i as usize % every == every - 1;
    let found = whole.ids.iter().filter(thrown).count();
    let surface_taken = whole.ids.len() - found;
    assert_eq!(found, n / every, "thrown points found");
    assert!(
        surface_taken < n / 200,
        "{surface_taken} surface points taken"
    );
}
