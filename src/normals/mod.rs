//! Oriented normals (paper 1 sections 2.2-2.4): tangent planes by PCA of the
//! exact k nearest neighbours (or, optionally, paper 3's topological
//! neighbours, see [`NormalHood`]), then orientation by a minimum spanning
//! tree over the Riemannian graph (exact in tiles: see [`forest`]) or toward
//! a scanner position.
//!
//! Results land in two store columns: `normal.f32` (unit, oriented; zero when
//! degenerate) and `flags.u8` ([`FLAG_DEGENERATE`], [`FLAG_UNORIENTED`]).

mod bad_parameter;
mod choice;
mod components;
mod contract;
pub mod eigen;
pub mod evaluate;
pub mod evidence;
pub mod forest;
pub(crate) mod hood;
pub(crate) mod kernel;
pub(crate) mod labels;
pub(crate) mod orient;
mod output;
mod packed;
pub mod pca;
pub(crate) mod runs;
pub mod sources;
mod stage;
mod summary;
pub(crate) mod unionfind;

use crate::pipeline::{run_stage, KernelCost, PipelineError, Progress, RunOptions, RunStats};
use crate::spatial::topological::TopoParams;
use crate::spatial::{HoodKind, KnnBackend};
use crate::store::sampling::SamplingStats;
use crate::store::{PointStore, Provenance, StoreError, FLAGS, NORMALS};
use glam::DVec3;

/// Bytes per point of an input-order output window of positions, normals
/// and flags (the record and its share of the reorder buffers).
pub(crate) const EXPORT_BYTES_PER_POINT: u64 = 48;

/// The neighbourhood was too small or degenerate (colinear, coincident) for
/// a tangent plane: the normal is zero, never made up.
pub const FLAG_DEGENERATE: u8 = 1;
/// The point has a normal but the orientation could not reach it (an island
/// dropped by the paper's 1/1000 rule). With the spanning tree, the normal
/// is still signed by its island's own highest points, not tied to the rest.
pub const FLAG_UNORIENTED: u8 = 2;

/// Normal `k` of a normals column read as flat f32 triples.
pub(crate) fn normal_at(raw: &[f32], k: usize) -> DVec3 {
    DVec3::new(
        f64::from(raw[3 * k]),
        f64::from(raw[3 * k + 1]),
        f64::from(raw[3 * k + 2]),
    )
}

/// How normals get their sign.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Orientation {
    /// From what the scan knows (the default, [`evidence::resolve`]):
    /// toward each point's own scan station when the input names stations
    /// (E57 poses), [`Orientation::Aerial`] for aerial data, else the
    /// spanning tree. The sensor hint overrides the guess.
    Auto(Sensor),
    /// The paper's minimum spanning tree over the Riemannian graph, each
    /// component signed by a vote of its columns' highest points.
    SpanningTree,
    /// Aerial: level normals face up, and the spanning tree, anchored to
    /// "up" by edges that cost more the steeper the normal, signs the rest
    /// (walls, overhangs; `orient::anchors`).
    Aerial,
    /// Each point toward its own scan's station (the store's stations:
    /// E57 scan poses).
    Stations,
    /// Toward a scanner position (absolute coordinates): single-station scans.
    Viewpoint(DVec3),
    /// Paper 5's six sources (extreme points along +-X, +-Y, +-Z), spread
    /// where `|n_i . n_j| >= tau` ([`sources`]).
    SixSources {
        /// Least `|n_i . n_j|` across which the orientation spreads, in `[0, 1]`.
        tau: f64,
    },
    /// One source, the point farthest along `direction` (single-sheet
    /// models, e.g. terrain with +Z).
    SingleSource {
        /// The direction the source point is farthest along (not zero).
        direction: DVec3,
        /// Least `|n_i . n_j|` across which the orientation spreads, in `[0, 1]`.
        tau: f64,
    },
    /// Leave the canonical PCA sign (largest component positive).
    None,
}

impl Orientation {
    /// Whether the spanning tree's global pass signs the normals.
    pub(crate) fn by_tree(&self) -> bool {
        matches!(self, Orientation::SpanningTree | Orientation::Aerial)
    }
}

pub use bad_parameter::BadNormalParameter;
pub use choice::{OrientationChoice, OrientationKind};
pub use evidence::{Evidence, EvidenceCheck, Sensor};
pub use output::normals_output;
pub use stage::{NormalsSeam, NormalsStage};

/// Cost of a Riemannian-graph edge for the spanning tree.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum EdgeCost {
    /// The paper's `1 - |n_i . n_j|`.
    #[value(help = "The paper's 1 - |ni.nj|")]
    Paper,
    /// Deviation (the default): the paper's cost plus the mean tangent-plane
    /// offset `(|d . n_i| + |d . n_j|) / 2|d|` of the edge `d = x_j - x_i`.
    /// Across a part thinner than the neighbourhood (a dragon's claw, two
    /// close sheets) the normals are antiparallel, so the paper's cost is
    /// near zero and the tree happily crosses, flipping a whole side; such
    /// an edge runs along the normals, so its offset is near 1 and the tree
    /// goes round instead. Within a sheet the offset is near 0.
    #[default]
    #[value(
        name = "offset",
        help = "Paper cost plus the edge's tangent-plane offset"
    )]
    TangentOffset,
}

/// Which neighbourhood a tangent plane (and the spanning tree's edges) uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum NormalHood {
    /// The exact k nearest neighbours (paper 1 section 2.2).
    #[default]
    Knn,
    /// Paper 3's topological neighbours (mean reverse shift over an R*-tree,
    /// [`crate::spatial::topological`]): k per query, so `|T|` lies in
    /// `[k, ~3k]`. Near a density change the k nearest crowd to the dense
    /// side; T adds the sparse side, which balances the plane fit.
    Topological {
        /// Cap on the mean reverse shift's iterations per point.
        max_iterations: usize,
    },
}

impl NormalHood {
    /// The neighbourhood of kind `kind` (topological: at most
    /// `max_iterations` reverse shifts per point).
    pub fn of(kind: HoodKind, max_iterations: usize) -> Self {
        match kind {
            HoodKind::Knn => NormalHood::Knn,
            HoodKind::Topological => NormalHood::Topological { max_iterations },
        }
    }

    /// The mean reverse shift's parameters for `k` neighbours per query
    /// (`None` for kNN).
    pub(crate) fn topo_params(&self, k: usize) -> Option<TopoParams> {
        match *self {
            NormalHood::Knn => None,
            NormalHood::Topological { max_iterations } => Some(TopoParams { k, max_iterations }),
        }
    }
}

/// How normals are computed: the tangent-plane neighbourhood and how the normals get their sign.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NormalParams {
    /// Neighbours per point besides the point itself (paper: 8..15); per
    /// query for the topological neighbourhood.
    pub k: usize,
    /// kNN structure (the topological neighbourhood uses paper 3's R*-tree).
    pub backend: KnnBackend,
    /// Which neighbourhood a tangent plane uses.
    pub neighbourhood: NormalHood,
    /// How the normals get their sign.
    pub orientation: Orientation,
    /// Cost of a spanning-tree edge (with [`Orientation::SpanningTree`]).
    pub cost: EdgeCost,
}

impl Default for NormalParams {
    fn default() -> Self {
        NormalParams {
            k: 12,
            backend: KnnBackend::default(),
            neighbourhood: NormalHood::default(),
            orientation: Orientation::Auto(Sensor::Auto),
            cost: EdgeCost::default(),
        }
    }
}

impl NormalParams {
    /// Whether the parameters can give normals: a plane needs 3 neighbours,
    /// a viewpoint or a source direction must be finite (and the direction
    /// not zero), tau a bound on `|ni.nj|` in `[0, 1]`.
    pub fn validate(&self) -> Result<(), NormalsError> {
        let bad = |why| Err(NormalsError::BadParameter(why));
        if self.k < 3 {
            return bad(BadNormalParameter::TooFewNeighbours { k: self.k });
        }
        match self.orientation {
            Orientation::Viewpoint(v) if !v.is_finite() => bad(BadNormalParameter::Viewpoint(v)),
            Orientation::SixSources { tau } | Orientation::SingleSource { tau, .. }
                if !(0.0..=1.0).contains(&tau) =>
            {
                bad(BadNormalParameter::Tau(tau))
            }
            Orientation::SingleSource { direction, .. }
                if !direction.is_finite() || direction == DVec3::ZERO =>
            {
                bad(BadNormalParameter::Direction(direction))
            }
            _ => Ok(()),
        }
    }

    /// The parameters as the manifest records them for the normals column.
    pub(crate) fn provenance(&self) -> Provenance {
        Provenance::of("normals", self)
    }

    /// Peak bytes per loaded point of the kernel (index, neighbour lists,
    /// normals, edges), for the memory planner. Topological: the R*-tree's
    /// entries and nodes (~40 more bytes a point) and lists of about 2k
    /// (paper 3: `|T|` in `[k, 3k]`).
    pub(crate) fn bytes_per_point(&self) -> u64 {
        let k = self.k as u64;
        match self.neighbourhood {
            NormalHood::Knn => 120 + 20 * k,
            NormalHood::Topological { .. } => 160 + 20 * 2 * k,
        }
    }

    /// What a normals run costs, for the memory plan: the kernel's bytes per
    /// loaded point, the orientation's union-find (or its contracted
    /// boundaries when that does not fit), and the output's records.
    pub fn cost(&self) -> KernelCost {
        let global = !matches!(
            self.orientation,
            Orientation::None | Orientation::Viewpoint(_) | Orientation::Stations
        );
        KernelCost {
            bytes_per_point: self.bytes_per_point(),
            global_per_point: if global { orient::BYTES_PER_POINT } else { 0 },
            contracts_boundaries: global,
            resident_per_point: 0.0,
            window_bytes_per_point: EXPORT_BYTES_PER_POINT,
            // Beside the store at the orientation, its peak: normals and
            // flags (13), the forest runs (24 B an edge merged, ~11
            // packed for the external pass, about one edge a point), the
            // neighbour slots (2) and the external pass's labels (4) and
            // super-edges (1.4-2.2). Measured on the 10M dragon (scratch
            // sampled every second, allocated blocks): 40.1 B in memory
            // (`--mem 256MiB`), 28.2 external (`--mem 128MiB`).
            scratch_per_point: 44,
            // While the output is written: normals and flags, and the
            // export's reorder file (slot, normal, flags: 17).
            export_scratch_per_point: 30,
            // A run directory keeps each tile's output until the run is
            // done: its normals, flags, neighbour slots and forest (24 B
            // an edge). Measured: 35.4 B on the 1M dragon, 38.9 on the
            // 10M (`--mem 256MiB`).
            checkpoint_per_point: 44,
            // The external pass's forest is packed (about 11 B an edge
            // where a merged record takes 24). Measured peaks beside the
            // store, external: 28.2 B on the 10M dragon, 27.8 on the
            // 100M (scratch sampled every second, allocated blocks).
            external_scratch_saving: 12,
            export_frees_positions: false,
            // x y z as double, normals as float, flags.
            output_per_point: 37,
            beside_output_per_point: 0,
            parallel_in_tile: false,
            margin_spacings: 0.0,
            resident_bytes: 0,
        }
    }

    /// First margin to try (see [`initial_margin`]): the reverse shift's
    /// reach is about twice the k-th neighbour distance (the shift plus the
    /// shifted query's radius), so the topological margin is doubled, as
    /// in [`crate::neighbours::NeighbourParams::initial_margin`].
    pub(crate) fn initial_margin(&self, spacing: f64) -> f64 {
        let factor = match self.neighbourhood {
            NormalHood::Knn => 1.0,
            NormalHood::Topological { .. } => 2.0,
        };
        factor * initial_margin(spacing, self.k)
    }
}

/// Errors of the normals pass.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum NormalsError {
    /// Reading or writing the store failed.
    #[error(transparent)]
    Store(#[from] StoreError),
    /// The tile pipeline failed.
    #[error(transparent)]
    Pipeline(#[from] PipelineError),
    /// Reading or writing a file failed.
    #[error(transparent)]
    Io(#[from] crate::io::IoError),
    /// The six-source (or single-source) orientation failed.
    #[error(transparent)]
    Sources(#[from] sources::SourcesError),
    /// The parameters cannot give normals; the message says which and why.
    #[error("normal parameters: {0}")]
    BadParameter(BadNormalParameter),
}

/// What the normals pass did.
#[derive(Clone, Copy, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct NormalsReport {
    /// Points given a normal (or flagged degenerate).
    pub points: u64,
    /// Tiles processed.
    pub tiles: usize,
    /// Points whose neighbourhood spans no plane: normal zero, flagged.
    pub degenerate: u64,
    /// Points with a normal the orientation could not reach: sign left as PCA gave it, flagged.
    pub unoriented: u64,
    /// Connected components the orientation found.
    pub components: usize,
    /// Edges of the spanning forest over all tiles.
    pub forest_edges: u64,
    /// Sampling density and noise measured on the way.
    pub sampling: SamplingStats,
    /// Tiles, retries and margins of the run.
    pub run: RunStats,
    /// How the normals were signed (what [`Orientation::Auto`] chose).
    #[serde(default)]
    pub oriented_by: OrientedBy,
    /// How many normals disagree with the scan's own evidence, when it
    /// has any ([`evidence`]).
    #[serde(default)]
    pub evidence: Option<EvidenceCheck>,
}

/// Which orientation a run used, once [`Orientation::Auto`] is resolved.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum OrientedBy {
    /// Not recorded (a report of an earlier version).
    #[default]
    Unknown,
    /// The spanning tree.
    SpanningTree,
    /// Up, the spanning tree anchored there (aerial).
    Aerial,
    /// Each point toward its scan's station.
    Stations,
    /// Toward one viewpoint.
    Viewpoint,
    /// Paper 5's six sources.
    SixSources,
    /// One source direction.
    SingleSource,
    /// Not oriented.
    None,
}

impl OrientedBy {
    fn of(o: Orientation) -> Self {
        match o {
            Orientation::Auto(_) => OrientedBy::Unknown,
            Orientation::SpanningTree => OrientedBy::SpanningTree,
            Orientation::Aerial => OrientedBy::Aerial,
            Orientation::Stations => OrientedBy::Stations,
            Orientation::Viewpoint(_) => OrientedBy::Viewpoint,
            Orientation::SixSources { .. } => OrientedBy::SixSources,
            Orientation::SingleSource { .. } => OrientedBy::SingleSource,
            Orientation::None => OrientedBy::None,
        }
    }

    /// What the summary calls it.
    pub fn describe(self) -> &'static str {
        match self {
            OrientedBy::Unknown => "unknown",
            OrientedBy::SpanningTree => "spanning tree",
            OrientedBy::Aerial => "aerial: up, tree past vertical",
            OrientedBy::Stations => "toward each scan's station",
            OrientedBy::Viewpoint => "toward the viewpoint",
            OrientedBy::SixSources => "six sources",
            OrientedBy::SingleSource => "single source",
            OrientedBy::None => "none",
        }
    }
}

/// First margin to try: two neighbourhood radii (core and ring points) for
/// a surface sampled at `spacing`, where the k-th neighbour lies at about
/// `1.13 sqrt(k)` spacings for uniform sampling (scans are not: 4 rather
/// than 2.3 spacings per sqrt(k)). The kernel asks for more when it is short.
pub(crate) fn initial_margin(spacing: f64, k: usize) -> f64 {
    4.0 * spacing * (k as f64).sqrt()
}

/// Computes oriented normals for every point of `store` into its columns:
/// [`run_stage`] of [`NormalsStage`].
pub fn compute_normals(
    store: &mut PointStore,
    params: &NormalParams,
    opts: RunOptions,
    progress: &dyn Progress,
) -> Result<NormalsReport, NormalsError> {
    run_stage(store, &NormalsStage { params: *params }, opts, progress)
}

/// Whether `store` holds normals computed with `params` (with their
/// sampling statistics): the ones a later pass may reuse.
pub fn has_normals_of(store: &PointStore, params: &NormalParams) -> bool {
    store.manifest().sampling.is_some()
        && store.provenance(&NORMALS) == Some(&params.provenance())
        && store.provenance(&FLAGS) == Some(&params.provenance())
}

/// Computes normals with `params` unless the store holds them already;
/// the report when it computed them.
pub(crate) fn ensure_normals(
    store: &mut PointStore,
    params: &NormalParams,
    opts: RunOptions,
    progress: &dyn Progress,
) -> Result<Option<NormalsReport>, NormalsError> {
    if has_normals_of(store, params) {
        return Ok(None);
    }
    compute_normals(store, params, opts, progress).map(Some)
}
