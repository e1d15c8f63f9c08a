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
//! Out of core like every stage, and the example of the stage contract
//! ([`OutliersStage`], a [`Stage`]): a tile kernel scores its core points
//! ([`ScoreKernel`]), the seam ([`ScoreSeam`]) writes the scores to a
//! store column and adds up order-free sums ([`crate::stats::ExactSum`]),
//! so the threshold, and with it every flag, is the same for any tiling
//! and thread count; a second pass over the column flags the outliers
//! when the seam finishes. The output is the store's point export with
//! the score and the flags as named fields, in any format the output
//! table gives ([`crate::io::output_spec`]).
//!
//! Deviation: a point of a cloud with fewer than `k + 1` points has fewer
//! than `k` neighbours; its score is over those it has, flagged
//! [`FEWER_THAN_K`], and it takes no part in the rule (PCL and Open3D
//! average over what the search returns and judge it like the others).

mod kernel;
mod seam;
mod summary;

pub use kernel::{ScoreKernel, TileScores};
pub use seam::ScoreSeam;
pub use summary::OutliersWritten;

use crate::io::{output_spec, Carried, IoError, ValueField, WriterSpec};
use crate::memory::KernelCost;
use crate::pipeline::{run_stage, PipelineError, RunOptions, RunStats};
use crate::pipeline::{Stage, StageColumns, StageParams};
use crate::progress::Progress;
use crate::store::spacing::ensure_spacing;
use crate::store::{
    export_values, ColumnSpec, Item, PointStore, Provenance, Rows, StageId, StoreError,
};
use kernel::Sums;
use std::path::Path;

/// The stage's id: its name in progress bars, logs and errors.
pub const OUTLIER_SCORES: StageId = StageId::new("outlier scores");
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
            export_scratch_per_point: 14,
            checkpoint_per_point: 0,
            external_scratch_saving: 0,
            export_frees_positions: false,
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

/// The outlier stage ([`Stage`]): the rule's parameters, run by
/// [`run_stage`] (or [`compute_outliers`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct OutliersStage {
    /// The rule.
    pub params: OutlierParams,
}

impl StageParams for OutlierParams {
    type Error = OutliersError;

    fn validate(&self) -> Result<(), OutliersError> {
        OutlierParams::validate(self)
    }

    fn cost(&self) -> KernelCost {
        OutlierParams::cost(self)
    }
}

impl Stage for OutliersStage {
    const ID: StageId = OUTLIER_SCORES;
    const READS: &'static [ColumnSpec] = &[];
    const WRITES: &'static [ColumnSpec] = &[OUTLIER_SCORE, OUTLIER_FLAGS];
    type Params = OutlierParams;
    type Kernel = ScoreKernel;
    type Seam<'s> = ScoreSeam<'s>;
    type Report = OutlierReport;
    type Error = OutliersError;

    fn params(&self) -> &OutlierParams {
        &self.params
    }

    fn provenance(&self) -> Provenance {
        Provenance::of("outliers", &self.params)
    }

    fn kernel(
        &self,
        store: &mut PointStore,
        _: RunOptions,
        _: &dyn Progress,
    ) -> Result<ScoreKernel, OutliersError> {
        let spacing = ensure_spacing(store)?;
        let k = self.params.k;
        Ok(ScoreKernel {
            k,
            margin: (2.0 * spacing * (k as f64).sqrt().max(2.0)).max(1e-9),
            scale: sum_scale(store),
            bytes_per_point: self.params.cost().bytes_per_point,
        })
    }

    fn seam<'s>(
        &'s self,
        store: &'s PointStore,
        kernel: &ScoreKernel,
        columns: &'s StageColumns,
    ) -> Result<ScoreSeam<'s>, OutliersError> {
        Ok(ScoreSeam {
            store,
            scores: columns.get(&OUTLIER_SCORE)?,
            flags: columns.get(&OUTLIER_FLAGS)?,
            sums: Sums::new(kernel.scale),
            params: self.params,
        })
    }
}

/// Scores every point of `store` and flags the outliers, in the columns
/// [`OUTLIER_SCORE`] and [`OUTLIER_FLAGS`]: [`run_stage`] of [`OutliersStage`].
pub fn compute_outliers(
    store: &mut PointStore,
    params: &OutlierParams,
    opts: RunOptions,
    progress: &dyn Progress,
) -> Result<OutlierReport, OutliersError> {
    run_stage(store, &OutliersStage { params: *params }, opts, progress)
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

/// Writes the store's points with their scores and flags to `rows` as
/// `spec` says ([`outliers_output`]), in input order. Returns the rows
/// written.
pub fn write_outliers(
    store: &PointStore,
    spec: &WriterSpec,
    rows: &Rows,
) -> Result<u64, OutliersError> {
    Ok(export_values(
        store,
        spec,
        [OUTLIER_SCORE, OUTLIER_FLAGS],
        rows,
    )?)
}
