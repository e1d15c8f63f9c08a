//! Statistical outlier scores (`scanmesh outliers`): each point's mean
//! distance to its `k` nearest neighbours, and the points whose score
//! exceeds the mean score by more than `ratio` standard deviations. This is
//! the rule of PCL's `StatisticalOutlierRemoval` (Rusu et al. 2008,
//! "Towards 3D point cloud based object maps for household environments",
//! sec. 4) and Open3D's `remove_statistical_outlier`: PCL's k nearest
//! other points (Open3D counts the point itself among its `nb_neighbors`,
//! which scales every score alike and flags the same points), both's
//! sample standard deviation, Open3D's usual k = 20, ratio = 2. No paper
//! of this project covers it; it is the stage that shows how a capability
//! plugs in (ARCHITECTURE.md, "Adding a stage").
//!
//! Out of core like every stage: a tile kernel scores its core points
//! (`kernel`), the seam writes the scores to a store column and adds up
//! order-free sums ([`crate::stats::ExactSum`]), so the threshold, and with
//! it every flag, is the same for any tiling and thread count; a second
//! pass over the column flags the outliers. The output is the store's
//! point export with the score and the flags as named fields, in any
//! format the output table gives ([`crate::io::output_spec`]).
//!
//! Deviation: a point of a cloud with fewer than `k + 1` points has fewer
//! than `k` neighbours; its score is over those it has, flagged
//! [`FEWER_THAN_K`], and it takes no part in the rule (PCL and Open3D
//! average over what the search returns and judge it like the others).

mod kernel;
mod summary;

pub use summary::OutliersWritten;

use crate::io::{output_spec, Carried, IoError, ValueField, WriterSpec};
use crate::memory::KernelCost;
use crate::pipeline::{run_tiles, PipelineError, RunOptions, RunStats};
use crate::progress::Progress;
use crate::store::spacing::ensure_spacing;
use crate::store::{export_values, ColumnSpec, Item, PointStore, Provenance, StoreError};
use kernel::{ScoreKernel, Sums};
use std::path::Path;

/// Per-point score: the mean distance to the `k` nearest (f32, input units).
pub const OUTLIER_SCORE: ColumnSpec = ColumnSpec::new("outlier_score.f32", Item::F32(1));
/// Per-point flags: [`OUTLIER`], [`FEWER_THAN_K`].
pub const OUTLIER_FLAGS: ColumnSpec = ColumnSpec::new("outlier_flags.u8", Item::U8);
/// Flag: the score exceeds the rule's threshold.
pub const OUTLIER: u8 = 1;
/// Flag: the whole cloud holds fewer than `k` other points; not judged.
pub const FEWER_THAN_K: u8 = 2;

/// The score's field in an output.
pub const OUTLIER_FIELDS: [ValueField; 1] = [ValueField {
    name: "outlier_score",
    description: "mean distance to the k nearest",
}];

const COMMENT: &str = "scanmesh outliers: outlier_score = mean distance to the k nearest \
     neighbours; flags 1 outlier (score above mean + ratio x standard deviation), 2 fewer than \
     k neighbours in the cloud (not judged), 128 not selected";

/// Peak bytes per loaded point of the kernel: the tile's points and ids
/// (32), the grid index (its sorted copy and cells, about 40), the scores
/// and flags (5), with room for the kNN buffers. Measured in
/// `tests/outliers.rs` against `--mem`.
const BYTES_PER_LOADED_POINT: u64 = 96;

/// The rule's parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OutlierParams {
    /// Neighbours whose mean distance is the score (Open3D's
    /// `nb_neighbors`, PCL's `mean_k`).
    pub k: usize,
    /// Standard deviations above the mean score past which a point is an
    /// outlier (Open3D's `std_ratio`, PCL's `stddev_mul_thresh`).
    pub ratio: f64,
}

impl Default for OutlierParams {
    fn default() -> Self {
        OutlierParams { k: 20, ratio: 2.0 }
    }
}

impl OutlierParams {
    /// Refuses k = 0, k past 1000 (a neighbourhood that is no longer
    /// local) and a ratio that is not a finite positive number.
    pub fn validate(&self) -> Result<(), OutliersError> {
        if !(1..=1000).contains(&self.k) {
            return Err(OutliersError::BadK { k: self.k });
        }
        if !(self.ratio.is_finite() && self.ratio > 0.0) {
            return Err(OutliersError::BadRatio { ratio: self.ratio });
        }
        Ok(())
    }

    /// What an `outliers` run costs, for the memory and disk plans.
    pub fn cost(&self) -> KernelCost {
        KernelCost {
            bytes_per_point: BYTES_PER_LOADED_POINT + 16 * self.k as u64,
            global_per_point: 0,
            contracts_boundaries: false,
            resident_per_point: 0.0,
            window_bytes_per_point: crate::normals::EXPORT_BYTES_PER_POINT,
            // The two columns (5), the export's reorder file (slot, score,
            // flags: 9).
            scratch_per_point: 14,
            // A PLY record: x y z double, the score, the flags.
            output_per_point: 29,
            beside_output_per_point: 0,
            parallel_in_tile: false,
            margin_spacings: 0.0,
            resident_bytes: 0,
        }
    }
}

/// Errors of the outlier stage.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum OutliersError {
    /// Reading or writing the store failed.
    #[error(transparent)]
    Store(#[from] StoreError),
    /// The tile pipeline failed.
    #[error(transparent)]
    Pipeline(#[from] PipelineError),
    /// Writing an output failed.
    #[error(transparent)]
    Io(#[from] IoError),
    /// `k` is outside 1..=1000.
    #[error("k must be 1 to 1000 neighbours, got {k}")]
    BadK {
        /// The `k` given.
        k: usize,
    },
    /// The ratio is not a finite positive number.
    #[error("ratio must be a positive number of standard deviations, got {ratio}")]
    BadRatio {
        /// The ratio given.
        ratio: f64,
    },
}

/// What the outlier pass found.
#[derive(Clone, Debug)]
pub struct OutlierReport {
    /// Points scored.
    pub points: u64,
    /// Mean score over the judged points.
    pub mean: f64,
    /// Their standard deviation (sample).
    pub std_dev: f64,
    /// The score past which a point is an outlier.
    pub threshold: f64,
    /// Points flagged [`OUTLIER`].
    pub outliers: u64,
    /// Points flagged [`FEWER_THAN_K`].
    pub not_judged: u64,
    /// How the tiles ran.
    pub run: RunStats,
    /// The rule the points were judged by.
    pub params: OutlierParams,
}

/// Scores every point of `store` and flags the outliers, in the columns
/// [`OUTLIER_SCORE`] and [`OUTLIER_FLAGS`].
pub fn compute_outliers(
    store: &mut PointStore,
    params: &OutlierParams,
    opts: RunOptions,
    progress: &dyn Progress,
) -> Result<OutlierReport, OutliersError> {
    params.validate()?;
    let spacing = ensure_spacing(store)?;
    let kernel = ScoreKernel {
        k: params.k,
        margin: (2.0 * spacing * (params.k as f64).sqrt().max(2.0)).max(1e-9),
        scale: sum_scale(store),
        bytes_per_point: params.cost().bytes_per_point,
    };
    let scores = store.create_column(&OUTLIER_SCORE)?;
    let flags = store.create_column(&OUTLIER_FLAGS)?;
    let mut sums = Sums::new(kernel.scale);
    let run = run_tiles(store, &kernel, opts, progress, |t, out| {
        let start = store.tiles()[t].start;
        scores.write_f32(start, &out.scores)?;
        flags.write_bytes(start, &out.flags)?;
        sums.merge(&out.sums);
        Ok(())
    })?;
    let mean = sums.score.mean();
    let n = sums.score.count() as f64;
    // The sample variance, as PCL and Open3D take it.
    let variance = (sums.square.mean() - mean * mean) * n / (n - 1.0).max(1.0);
    let std_dev = variance.max(0.0).sqrt();
    let threshold = mean + params.ratio * std_dev;
    let (mut outliers, mut not_judged) = (0, 0);
    let (mut s, mut f) = (Vec::new(), Vec::new());
    for t in store.tiles() {
        scores.read_f32(t.start, t.count, &mut s)?;
        flags.read_u8(t.start, t.count, &mut f)?;
        for (flag, score) in f.iter_mut().zip(&s) {
            if *flag == 0 && f64::from(*score) > threshold {
                *flag = OUTLIER;
            }
            outliers += u64::from(*flag == OUTLIER);
            not_judged += u64::from(*flag == FEWER_THAN_K);
        }
        flags.write_bytes(t.start, &f)?;
    }
    let made_by = Provenance::of("outliers", params);
    store.finish_column(&OUTLIER_SCORE, &scores, made_by.clone())?;
    store.finish_column(&OUTLIER_FLAGS, &flags, made_by)?;
    Ok(OutlierReport {
        points: store.len(),
        mean,
        std_dev,
        threshold,
        outliers,
        not_judged,
        run,
        params: *params,
    })
}

/// The unit of the order-free sums: from the input's bounds, which no
/// tiling changes (the spacing is estimated from a sample of the store's
/// layout, and a sum in other units rounds to other bits). 2^-20 of the
/// diagonal keeps about 60 bits of a score; a score past 10^11 diagonals
/// saturates.
fn sum_scale(store: &PointStore) -> f64 {
    let m = store.manifest();
    let diagonal = (0..3)
        .map(|a| (m.bounds_max[a] - m.bounds_min[a]).powi(2))
        .sum::<f64>()
        .sqrt();
    match diagonal > 0.0 && diagonal.is_finite() {
        true => diagonal / f64::from(1u32 << 20),
        false => 1.0,
    }
}

/// The writer spec of an outliers output named `path`: an error names the
/// file when its format cannot hold the score.
pub fn outliers_output(path: &Path) -> Result<WriterSpec, IoError> {
    output_spec(
        path,
        &Carried::values_and_flags(&OUTLIER_FIELDS, COMMENT),
        false,
    )
}

/// Writes the store's points with their scores and flags to `path` as
/// `spec` says ([`outliers_output`]), in input order, holding about
/// `window` points in memory; `keep` as [`crate::store::export_columns`].
/// Returns the rows written.
pub fn write_outliers(
    store: &PointStore,
    path: &Path,
    spec: &WriterSpec,
    window: u64,
    keep: Option<(&Path, &crate::io::ReadOptions)>,
    progress: &dyn Progress,
) -> Result<u64, OutliersError> {
    let columns = [OUTLIER_SCORE, OUTLIER_FLAGS];
    Ok(export_values(
        store, path, spec, columns, window, keep, progress,
    )?)
}
