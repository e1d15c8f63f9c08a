//! The normals as a stage ([`NormalsStage`], a [`Stage`]): the kernel
//! prepared for the store (the orientation resolved from what the scan
//! knows, the spacing, the histograms' scale), and the seam
//! ([`NormalsSeam`]): each tile's normals and flags into their columns, its
//! spanning forest appended to the edge runs (anchored to "up" for aerial
//! data), its sampling histograms merged; once every tile is in, the global
//! orientation (the spanning tree in memory or external, or the six
//! sources), the check against the scan's own evidence, and the sampling
//! statistics recorded in the manifest before the columns are sealed.

use super::kernel::{NormalsKernel, NormalsTile};
use super::runs::{EdgeRuns, Layout};
use super::{evidence, orient, sources, Evidence, NormalParams, NormalsError, NormalsReport};
use super::{Orientation, OrientedBy, Sensor, FLAG_DEGENERATE};
use crate::memory::KernelCost;
use crate::pipeline::StageParams;
use crate::pipeline::{PipelineError, RunOptions, RunStats, Seam, Stage, StageColumns};
use crate::progress::Progress;
use crate::store::sampling::SamplingHistograms;
use crate::store::{Column, ColumnSpec, PointStore, Provenance, StageId, FLAGS, NORMALS};
use glam::DVec3;

/// The normals stage: its parameters, run by [`crate::pipeline::run_stage`]
/// (or [`super::compute_normals`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct NormalsStage {
    /// The parameters as given ([`Orientation::Auto`] unresolved: the
    /// columns record them so).
    pub params: NormalParams,
}

impl StageParams for NormalParams {
    type Error = NormalsError;

    fn validate(&self) -> Result<(), NormalsError> {
        NormalParams::validate(self)
    }

    fn cost(&self) -> KernelCost {
        NormalParams::cost(self)
    }
}

impl Stage for NormalsStage {
    const ID: StageId = StageId::NORMALS;
    const READS: &'static [ColumnSpec] = &[];
    const WRITES: &'static [ColumnSpec] = &[NORMALS, FLAGS];
    type Params = NormalParams;
    type Kernel = NormalsKernel;
    type Seam<'s> = NormalsSeam<'s>;
    type Report = NormalsReport;
    type Error = NormalsError;

    fn params(&self) -> &NormalParams {
        &self.params
    }

    fn provenance(&self) -> Provenance {
        self.params.provenance()
    }

    /// The orientation resolved ([`evidence::resolve`]), the spacing, and
    /// the histograms' scale from the input bounds (the spacing estimate
    /// depends on the tiling, through its sample; the scale must not).
    fn kernel(
        &self,
        store: &mut PointStore,
        opts: RunOptions,
        _: &dyn Progress,
    ) -> Result<NormalsKernel, NormalsError> {
        let params = NormalParams {
            orientation: evidence::resolve(self.params.orientation, store)?,
            ..self.params
        };
        let spacing = crate::store::spacing::ensure_spacing(store)?;
        let extent = store.relative_bounds().extent().max_element();
        let scale = if extent > 0.0 { extent / 4096.0 } else { 1.0 };
        Ok(NormalsKernel {
            params,
            origin: store.origin(),
            initial_margin: params.initial_margin(spacing),
            spacing,
            histogram_scale: scale,
            stations: evidence::StationTable::new(&store.manifest().stations, store.origin()),
            external_orientation: !opts.holds(store.len(), orient::BYTES_PER_POINT),
        })
    }

    fn seam<'s>(
        &'s self,
        store: &'s PointStore,
        kernel: &NormalsKernel,
        columns: &'s StageColumns,
    ) -> Result<NormalsSeam<'s>, NormalsError> {
        let params = kernel.params;
        let external = kernel.external_orientation;
        let runs = EdgeRuns::create(
            &store.dir().join(".forest.edges"),
            Layout::for_orientation(external),
        )?;
        let anchoring = match params.orientation {
            Orientation::Aerial => orient::anchors::Anchoring::new(DVec3::Z, store.len()),
            _ => None,
        };
        let isolated = params
            .orientation
            .by_tree()
            .then(|| orient::Isolated::create(store))
            .transpose()?;
        Ok(NormalsSeam {
            store,
            normals: columns.get(&NORMALS)?,
            flags: columns.get(&FLAGS)?,
            params,
            sensor: match self.params.orientation {
                Orientation::Auto(sensor) => sensor,
                _ => Sensor::Auto,
            },
            spacing: kernel.spacing,
            sampling: SamplingHistograms::new(kernel.histogram_scale),
            runs,
            external,
            anchoring,
            isolated,
            ids: Vec::new(),
            report: NormalsReport {
                points: store.len(),
                tiles: store.tiles().len(),
                ..NormalsReport::default()
            },
        })
    }

    /// The sampling statistics, which later passes read from the manifest.
    fn record(&self, store: &mut PointStore, report: &NormalsReport) -> Result<(), NormalsError> {
        Ok(store.set_sampling(report.sampling)?)
    }
}

/// The normals' seam over a store and its two columns.
pub struct NormalsSeam<'s> {
    store: &'s PointStore,
    normals: &'s Column,
    flags: &'s Column,
    /// The parameters, the orientation resolved.
    params: NormalParams,
    /// The sensor the evidence is read for.
    sensor: Sensor,
    spacing: f64,
    sampling: SamplingHistograms,
    runs: EdgeRuns,
    /// The orientation goes external: its runs are packed.
    external: bool,
    anchoring: Option<orient::anchors::Anchoring>,
    isolated: Option<orient::Isolated>,
    /// A tile's input-order ids (aerial anchoring, packed runs).
    ids: Vec<u64>,
    report: NormalsReport,
}

impl Seam for NormalsSeam<'_> {
    type Tile = NormalsTile;
    type Report = NormalsReport;
    type Error = NormalsError;

    fn accept(&mut self, t: usize, out: NormalsTile) -> Result<(), PipelineError> {
        let store = self.store;
        let start = store.tiles()[t].start;
        let flat: Vec<f32> = out.normals.iter().flatten().copied().collect();
        self.normals.write_f32(start, &flat)?;
        self.flags.write_bytes(start, &out.flags)?;
        self.report.degenerate += out
            .flags
            .iter()
            .filter(|f| **f & FLAG_DEGENERATE != 0)
            .count() as u64;
        if let Some(isolated) = &self.isolated {
            isolated.write(start, &out.nn_slots)?;
        }
        let tile = &store.tiles()[t];
        let core = tile.start..tile.start + tile.count;
        self.ids.clear();
        if self.anchoring.is_some() || self.external {
            store.read_indices(tile.start, tile.count, &mut self.ids)?;
        }
        match &self.anchoring {
            Some(a) => {
                let forest = a.forest(out.forest, core.clone(), &self.ids, &flat, &out.flags);
                self.runs.push_tile_run(&forest, core, &self.ids)?;
            }
            None => self.runs.push_tile_run(&out.forest, core, &self.ids)?,
        }
        self.sampling.merge(&out.sampling);
        Ok(())
    }

    fn finish(
        self,
        run: RunStats,
        opts: RunOptions,
        progress: &dyn Progress,
    ) -> Result<NormalsReport, NormalsError> {
        let (store, params, spacing) = (self.store, &self.params, self.spacing);
        let (normals, flags) = (self.normals, self.flags);
        let mut report = self.report;
        report.run = run;
        report.sampling = self.sampling.stats();
        report.forest_edges = self.runs.edges();
        if let Some(mut isolated) = self.isolated {
            let sampling = &self.sampling;
            isolated.settle(&sampling.nn, sampling.isolation_limit());
            let b = store.relative_bounds();
            let columns = orient::Columns {
                normals,
                flags,
                isolated: &isolated,
                grid: orient::ColumnGrid::new([b.min.x, b.min.y], [b.max.x, b.max.y]),
                sky: self.anchoring.is_some(),
            };
            let stats = if self.external {
                orient::orient_external(store, self.runs, columns, progress)?
            } else {
                orient::orient_by_forest(store, self.runs, columns, progress)?
            };
            report.unoriented = stats.unoriented;
            report.components = stats.components;
        }
        // The exact mean over every point (independent of the tiling), unless
        // all points are duplicates.
        let nn = match report.sampling.mean_nn {
            m if m > 0.0 && m.is_finite() => m,
            _ => spacing,
        };
        if let Some(sp) = sources::SourceParams::for_normals(params, nn) {
            let stats = sources::orient_store(store, &sp, spacing, opts, progress, normals, flags)?;
            report.unoriented = stats.unoriented;
            report.components = stats.components;
            report.forest_edges = stats.forest_edges;
        }
        report.oriented_by = OrientedBy::of(params.orientation);
        if let Some(e) = Evidence::of(store, self.sensor) {
            report.evidence = Some(evidence::check(store, e, normals, flags)?);
        }
        Ok(report)
    }
}
