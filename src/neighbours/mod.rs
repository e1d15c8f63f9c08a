//! Neighbourhoods of every point, written in input order (issue 4): the
//! topological neighbours of paper 3 (mean reverse shift, see
//! [`crate::spatial::topological`]) or the plain k nearest neighbours.
//!
//! Data flow: [`kernel::NeighboursKernel`] runs on every tile and checks at
//! run time that each core point's neighbourhood lies inside the loaded
//! region (asking for a wider margin otherwise), so a tiled run gives the
//! untiled lists exactly. Results arrive in tile (spatial) order but the
//! output is in input order:
//!
//! 1. each tile's records, sorted by id, are appended to a scratch file with
//!    a per-tile index of output-window boundaries (`spill`);
//! 2. a final pass fills one window of consecutive input ids at a time (one
//!    contiguous byte range per tile, like `store::export`) and appends it to
//!    the output (`csr`: binary CSR or text), written under a temporary
//!    name and renamed into place only when complete.
//!
//! Memory is the tiles in flight plus one window of lists (sized by the
//! caller), never a structure per point of the whole cloud. Ids are 0-based
//! positions in the input among the points kept (the store's `index.u32`).
//!
//! Measured (release, 2 shared cores under load ~7, 1M points sampled from
//! the dragon, k = 15): topological 24 s, peak 284 MiB at `--mem 1GiB` and
//! 46 MiB at `--mem 128MiB` (64 tiles, byte-identical output); kNN 3.9 s.
//! Iterations: median 1, max 5, none capped; |T| 15..45, mean 17.2.

pub(crate) mod csr;
mod kernel;
pub(crate) mod spill;
mod stats;
mod summary;

pub use csr::{read_csr, Csr, IdWidth, OutputFormat};
pub use kernel::{NeighboursKernel, NeighboursTile};
pub use spill::ScratchFault;
pub use stats::{HoodStats, Summary};

use crate::io::IoError;
use crate::pipeline::{run_stage, KernelCost, PipelineError, Progress, RunOptions, RunStats};
use crate::pipeline::{Seam, Stage, StageColumns, StageParams};
use crate::spatial::topological::TopoParams;
use crate::spatial::{HoodKind, KnnBackend};
use crate::store::{ColumnSpec, PointStore, Provenance, StageId, StoreError};
use csr::WindowLists;
use spill::{Spill, Windows};
use std::path::Path;

/// Largest k accepted: neighbourhoods are for local geometry, and a larger k
/// would mostly make tiles (and their margins) absurdly large.
pub const MAX_K: usize = 4096;

/// Which neighbourhood every point gets.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Neighbourhood {
    /// Paper 3's topological neighbours (k per query, capped iterations).
    Topological(TopoParams),
    /// The exact k nearest neighbours.
    Knn {
        /// Neighbours per point, the point itself excluded.
        k: usize,
    },
}

/// What the neighbours pass computes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct NeighbourParams {
    /// Which neighbourhood every point gets.
    pub neighbourhood: Neighbourhood,
    /// kNN structure for [`Neighbourhood::Knn`] (the topological mode uses
    /// the paper's R*-tree).
    pub backend: KnnBackend,
}

impl Default for NeighbourParams {
    fn default() -> Self {
        NeighbourParams {
            neighbourhood: Neighbourhood::Topological(TopoParams::default()),
            backend: KnnBackend::default(),
        }
    }
}

impl NeighbourParams {
    /// `k` neighbours of kind `kind` (topological: at most
    /// `max_iterations` reverse shifts per point), default backend.
    pub fn of(kind: HoodKind, k: usize, max_iterations: usize) -> Self {
        match kind {
            HoodKind::Topological => Self::topological(k, max_iterations),
            HoodKind::Knn => Self::knn(k),
        }
    }

    /// The exact `k` nearest neighbours, default backend.
    pub fn knn(k: usize) -> Self {
        NeighbourParams {
            neighbourhood: Neighbourhood::Knn { k },
            ..Self::default()
        }
    }

    /// Paper 3's topological neighbours of `k` per query, at most `max_iterations` reverse shifts.
    pub fn topological(k: usize, max_iterations: usize) -> Self {
        NeighbourParams {
            neighbourhood: Neighbourhood::Topological(TopoParams { k, max_iterations }),
            ..Self::default()
        }
    }

    /// The `k` of either neighbourhood.
    pub fn k(&self) -> usize {
        match self.neighbourhood {
            Neighbourhood::Topological(p) => p.k,
            Neighbourhood::Knn { k } => k,
        }
    }

    /// `topological` or `knn`.
    pub fn mode_name(&self) -> &'static str {
        match self.neighbourhood {
            Neighbourhood::Topological(_) => "topological",
            Neighbourhood::Knn { .. } => "knn",
        }
    }

    /// Typical neighbours per point: k, or 2k for topological (paper 3:
    /// |T| in [k, 3k]).
    pub(crate) fn expected_size(&self) -> u64 {
        match self.neighbourhood {
            Neighbourhood::Topological(p) => 2 * p.k as u64,
            Neighbourhood::Knn { k } => k as u64,
        }
    }

    /// Peak bytes per loaded point of the kernel (points, ids, index, the
    /// core lists in local and global ids), for the memory planner.
    pub(crate) fn bytes_per_point(&self) -> u64 {
        120 + 12 * 3 * self.k() as u64
    }

    /// What a neighbours run costs, for the memory plan (no global pass).
    pub fn cost(&self) -> KernelCost {
        KernelCost {
            bytes_per_point: self.bytes_per_point(),
            global_per_point: 0,
            contracts_boundaries: false,
            resident_per_point: 0.0,
            window_bytes_per_point: self.window_bytes_per_point(),
            // Beside the store: the spilled lists and their index
            // (measured at the default, 30 expected: 135 B on the 1M
            // dragon, 130 B on a 110k LAS).
            scratch_per_point: 16 + 4 * self.expected_size(),
            export_scratch_per_point: 16 + 4 * self.expected_size(),
            checkpoint_per_point: 0,
            external_scratch_saving: 0,
            export_frees_positions: false,
            output_per_point: 8 + 4 * self.expected_size(),
            beside_output_per_point: 0,
            parallel_in_tile: false,
            margin_spacings: 0.0,
            resident_bytes: 0,
        }
    }

    /// Bytes per point of an output window (decoded lists, scratch records).
    pub(crate) fn window_bytes_per_point(&self) -> u64 {
        40 + 16 * self.expected_size()
    }

    /// First margin to try, for a surface sampled at `spacing`: the k-th
    /// neighbour lies near `1.13 sqrt(k)` spacings on uniform samples (more
    /// on scans); the reverse shift's reach adds the shift, about one more
    /// radius. The kernel asks for more when it is short.
    pub(crate) fn initial_margin(&self, spacing: f64) -> f64 {
        let factor = match self.neighbourhood {
            Neighbourhood::Topological(_) => 6.0,
            Neighbourhood::Knn { .. } => 3.0,
        };
        factor * spacing * (self.k() as f64).sqrt()
    }

    /// Refuses a `k` outside `1..=MAX_K`.
    pub fn validate(&self) -> Result<(), NeighboursError> {
        let k = self.k();
        if !(1..=MAX_K).contains(&k) {
            return Err(NeighboursError::BadParams { k });
        }
        Ok(())
    }
}

/// How the lists are written.
#[derive(Clone, Copy, Debug)]
pub struct OutputOptions {
    /// The file format of the lists.
    pub format: OutputFormat,
    /// Points per output window (memory: see
    /// `NeighbourParams::window_bytes_per_point`).
    pub window_points: u64,
}

/// Errors of the neighbours pass.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum NeighboursError {
    /// Reading or writing the store failed.
    #[error(transparent)]
    Store(#[from] StoreError),
    /// The tile pipeline failed.
    #[error(transparent)]
    Pipeline(#[from] PipelineError),
    /// Writing the output failed.
    #[error(transparent)]
    Io(#[from] IoError),
    /// The parameters are out of range.
    #[error("bad neighbourhood parameters: k = {k}: must be in 1..={MAX_K}")]
    BadParams {
        /// The `k` given, outside `1..=MAX_K`.
        k: usize,
    },
    /// The spilled per-tile lists do not add up (a damaged scratch file).
    #[error("neighbour scratch records are inconsistent: {fault}")]
    Scratch {
        /// What does not add up.
        fault: ScratchFault,
    },
}

/// What the neighbours pass did.
#[derive(Clone, Debug, Default)]
pub struct NeighboursReport {
    /// Points given a list.
    pub points: u64,
    /// Tiles processed.
    pub tiles: usize,
    /// Total neighbour entries written.
    pub neighbours: u64,
    /// Size and iteration histograms over all points.
    pub stats: HoodStats,
    /// Tiles, retries and margins of the run.
    pub run: RunStats,
    /// What the pass computed.
    pub params: NeighbourParams,
}

impl NeighboursReport {
    /// The `--summary` document.
    pub fn summary(&self, params: &NeighbourParams, seconds: f64) -> Summary {
        let k = params.k();
        Summary {
            mode: params.mode_name(),
            k,
            points: self.points,
            tiles: self.tiles,
            tiles_reloaded: self.run.retries,
            largest_margin: self.run.largest_margin,
            neighbours: self.neighbours,
            size: stats::SizeSummary::of(&self.stats, k),
            iterations: match params.neighbourhood {
                Neighbourhood::Topological(p) => {
                    stats::IterationSummary::of(&self.stats, p.max_iterations)
                }
                Neighbourhood::Knn { .. } => None,
            },
            seconds,
        }
    }

    /// Writes the `--summary` document of a run that took `seconds` to
    /// `path` (pretty JSON and an end of line), whole or not at all.
    pub fn write_summary(&self, path: &Path, seconds: f64) -> Result<(), IoError> {
        let summary = self.summary(&self.params, seconds);
        let mut text = serde_json::to_string_pretty(&summary)
            .map_err(|e| IoError::os(path, std::io::Error::other(e)))?;
        text.push('\n');
        let mut file = crate::io::AtomicFile::create(path)?;
        std::io::Write::write_all(file.file(), text.as_bytes())
            .map_err(|e| IoError::os(path, e))?;
        file.commit()
    }
}

/// The neighbours stage ([`Stage`]): every point's list, written to a file
/// in input order; run by [`run_stage`] (or [`compute_neighbours`]).
#[derive(Clone, Copy, Debug)]
pub struct NeighboursStage<'a> {
    /// Which neighbourhood every point gets.
    pub params: NeighbourParams,
    /// The output file.
    pub output: &'a Path,
    /// How the lists are written.
    pub out: OutputOptions,
}

impl StageParams for NeighbourParams {
    type Error = NeighboursError;

    fn validate(&self) -> Result<(), NeighboursError> {
        NeighbourParams::validate(self)
    }

    fn cost(&self) -> KernelCost {
        NeighbourParams::cost(self)
    }
}

impl Stage for NeighboursStage<'_> {
    const ID: StageId = StageId::NEIGHBOURS;
    const READS: &'static [ColumnSpec] = &[];
    const WRITES: &'static [ColumnSpec] = &[];
    type Params = NeighbourParams;
    type Kernel = NeighboursKernel;
    type Seam<'s>
        = NeighboursSeam
    where
        Self: 's;
    type Report = NeighboursReport;
    type Error = NeighboursError;

    fn params(&self) -> &NeighbourParams {
        &self.params
    }

    /// Writes no column: what its columns would record.
    fn provenance(&self) -> Provenance {
        Provenance::of(Self::ID.name(), &self.params)
    }

    fn kernel(
        &self,
        store: &mut PointStore,
        _: RunOptions,
        _: &dyn Progress,
    ) -> Result<NeighboursKernel, NeighboursError> {
        let spacing = crate::store::spacing::ensure_spacing(store)?;
        Ok(NeighboursKernel {
            params: self.params,
            initial_margin: self.params.initial_margin(spacing).max(f64::MIN_POSITIVE),
        })
    }

    /// Opens the output (an unwritable one fails before the tiles) and the
    /// scratch file of the lists.
    fn seam<'s>(
        &'s self,
        store: &'s PointStore,
        _: &NeighboursKernel,
        _: &'s StageColumns,
    ) -> Result<NeighboursSeam, NeighboursError> {
        let writer = csr::ListWriter::create(self.output, self.out.format, store.len())?;
        let windows = Windows::new(store.len(), self.out.window_points);
        let spill = Spill::create(store.dir(), windows, IdWidth::for_points(store.len()))?;
        let report = NeighboursReport {
            points: store.len(),
            tiles: store.tiles().len(),
            params: self.params,
            ..NeighboursReport::default()
        };
        Ok(NeighboursSeam {
            writer,
            windows,
            spill,
            report,
        })
    }
}

/// The neighbours' seam: each tile's lists spilled, sorted by id, to a
/// scratch file; at the end the file written window by window in input
/// order and renamed into place.
pub struct NeighboursSeam {
    writer: csr::ListWriter,
    windows: Windows,
    spill: Spill,
    report: NeighboursReport,
}

impl Seam for NeighboursSeam {
    type Tile = NeighboursTile;
    type Report = NeighboursReport;
    type Error = NeighboursError;

    fn accept(&mut self, _: usize, tile: NeighboursTile) -> Result<(), PipelineError> {
        self.report.stats.merge(&tile.stats);
        Ok(self.spill.push_tile(&tile)?)
    }

    fn finish(
        self,
        run: RunStats,
        _: RunOptions,
        progress: &dyn Progress,
    ) -> Result<NeighboursReport, NeighboursError> {
        let (mut writer, mut report) = (self.writer, self.report);
        report.run = run;
        report.neighbours = report.stats.total();
        let mut reader = self.spill.finish()?;
        let mut lists = WindowLists::default();
        progress.begin("write", report.points);
        for w in 0..self.windows.count() {
            reader.read_window(w, &mut lists)?;
            writer.write_window(&lists)?;
            progress.advance(lists.len() as u64);
        }
        progress.end();
        writer.commit()?;
        Ok(report)
    }
}

/// Computes every point's neighbourhood and writes the lists to `output` in
/// input order: [`run_stage`] of [`NeighboursStage`]. Nothing appears at
/// `output` unless the run succeeds.
pub fn compute_neighbours(
    store: &mut PointStore,
    params: &NeighbourParams,
    output: &Path,
    out: &OutputOptions,
    opts: RunOptions,
    progress: &dyn Progress,
) -> Result<NeighboursReport, NeighboursError> {
    let stage = NeighboursStage {
        params: *params,
        output,
        out: *out,
    };
    run_stage(store, &stage, opts, progress)
}
