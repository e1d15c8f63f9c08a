//! The curvature pass (paper 5 section 2): per point, the quadric of its
//! neighbourhood in the PCA frame oriented by the store's normals
//! (`super::quadric`), and at the point `k1 >= k2`, `H`, `K` and the fit's
//! RMS residual, into the store columns [`super::CURVATURE`] and
//! [`super::CURVATURE_FLAGS`].
//!
//! Seam policy: per-point local. A core point's value depends on its
//! neighbourhood only, found exactly (ties by input id) and checked to lie
//! inside the loaded region, so every tiling gives the same bits.

use super::hood::{HoodIndex, HoodScratch};
use super::quadric::{fit_quadric, pca_frame, Curvature, Quadric};
use super::stats::CurvatureStats;
use super::{
    CurvatureHood, CurvatureParams, FeaturesError, HoodChoice, CURVATURE, CURVATURE_FLAGS,
    CURVATURE_META_FILE, FLAG_UNORIENTED,
};
use crate::memory::KernelCost;
use crate::normals::{
    ensure_normals, FLAG_DEGENERATE as N_DEGENERATE, FLAG_UNORIENTED as N_UNORIENTED,
};
use crate::pipeline::{run_stage, KernelError, PipelineError, Progress, RunOptions, RunStats};
use crate::pipeline::{Seam, Stage, StageColumns, StageParams, TileKernel};
use crate::spatial::Neighbour;
use crate::store::{spacing::ensure_spacing, Column, ColumnSpec, PointStore, Provenance, StageId};
use crate::store::{FLAGS, NORMALS};
use crate::tiling::TilePoints;
use glam::DVec3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// f32 values per point in the curvature column.
pub const VALUES: usize = 5;

/// One tile's curvature of its core points.
pub struct CurvatureTile {
    /// `k1, k2, H, K, residual` per core point.
    pub(crate) values: Vec<f32>,
    /// Flags per core point.
    pub(crate) flags: Vec<u8>,
    pub(crate) stats: CurvatureStats,
}

/// The curvature's tile kernel: each core point's quadric and curvatures.
pub struct CurvatureKernel {
    pub(crate) hood: CurvatureHood,
    pub(crate) margin: f64,
    /// Mean spacing `d` (the statistics' scale).
    pub(crate) spacing: f64,
    /// Whether preparing the kernel computed the normals first (the store
    /// had none): reported, not read by the kernel.
    pub(crate) computed_normals: bool,
}

/// The oriented normal of loaded point `i`, if the normals pass gave one.
pub(crate) fn oriented_normal(tile: &TilePoints, i: usize) -> Option<DVec3> {
    let n = *tile.normals()?.get(i)?;
    let f = tile.flags()?.get(i).copied().unwrap_or(N_DEGENERATE);
    let ok = f & (N_DEGENERATE | N_UNORIENTED) == 0 && n.is_finite() && n != DVec3::ZERO;
    ok.then_some(n)
}

/// The quadric of point `i` and its neighbours `nbrs` (the point first,
/// then neighbours in their order), its frame's normal turned toward
/// `toward` (canonical PCA sign when `None`).
pub(crate) fn point_quadric(
    points: &[DVec3],
    i: usize,
    nbrs: &[Neighbour],
    toward: Option<DVec3>,
    buf: &mut Vec<DVec3>,
) -> Result<Quadric, u8> {
    buf.clear();
    buf.push(points[i]);
    buf.extend(nbrs.iter().map(|n| points[n.index as usize]));
    let frame = pca_frame(buf, toward.unwrap_or(DVec3::ZERO))?;
    fit_quadric(buf, frame)
}

/// The curvatures of a fitted quadric at the point it was fitted for.
pub(crate) fn curvature_of(q: &Quadric, p: DVec3) -> Curvature {
    let l = q.frame.local(p);
    q.curvature_at(l.x, l.y)
}

impl CurvatureKernel {
    /// Values and flags of loaded point `i`, and how far its
    /// neighbourhood reaches beyond the loaded region.
    fn point(
        &self,
        tile: &TilePoints,
        index: &HoodIndex,
        i: usize,
        s: &mut (HoodScratch, Vec<DVec3>),
    ) -> Result<([f32; VALUES], u8, f64, Option<Quadric>), KernelError> {
        let reach = index.query(tile, i, &mut s.0)?;
        let short = reach - tile.room(tile.points[i]);
        let toward = oriented_normal(tile, i);
        let nan = f32::NAN;
        Ok(
            match point_quadric(&tile.points, i, &s.0.nbrs, toward, &mut s.1) {
                Err(flag) => ([nan; VALUES], flag, short, None),
                Ok(q) => {
                    let c = curvature_of(&q, tile.points[i]);
                    let k = [c.k1, c.k2, c.mean, c.gauss, q.rms].map(|v| v as f32);
                    match toward {
                        Some(_) => (k, 0, short, Some(q)),
                        None => ([nan, nan, nan, k[3], k[4]], FLAG_UNORIENTED, short, Some(q)),
                    }
                }
            },
        )
    }
}

impl TileKernel for CurvatureKernel {
    type Output = CurvatureTile;

    fn name(&self) -> &'static str {
        CurvatureStage::ID.name()
    }

    fn margin(&self) -> f64 {
        self.margin
    }

    fn reads(&self) -> &[ColumnSpec] {
        CurvatureStage::READS
    }

    fn run(&self, tile: &TilePoints) -> Result<CurvatureTile, KernelError> {
        let index = HoodIndex::build(tile, self.hood)?;
        let parts: Vec<(CurvatureTile, f64)> = (0..tile.n_core.div_ceil(CHUNK))
            .into_par_iter()
            .map_init(
                || (HoodScratch::default(), Vec::new()),
                |s, c| self.chunk(tile, &index, c * CHUNK..tile.n_core.min((c + 1) * CHUNK), s),
            )
            .collect::<Result<_, _>>()?;
        let mut out = CurvatureTile {
            values: Vec::with_capacity(tile.n_core * VALUES),
            flags: Vec::with_capacity(tile.n_core),
            stats: CurvatureStats::new(self.spacing),
        };
        let mut short = 0.0f64;
        for (part, sh) in parts {
            out.values.extend(part.values);
            out.flags.extend(part.flags);
            out.stats.merge(&part.stats);
            short = short.max(sh);
        }
        KernelError::unless_short(short, tile.margin)?;
        Ok(out)
    }
}

/// Points per parallel task.
const CHUNK: usize = 2048;

impl CurvatureKernel {
    fn chunk(
        &self,
        tile: &TilePoints,
        index: &HoodIndex,
        range: std::ops::Range<usize>,
        s: &mut (HoodScratch, Vec<DVec3>),
    ) -> Result<(CurvatureTile, f64), KernelError> {
        let mut out = CurvatureTile {
            values: Vec::with_capacity(range.len() * VALUES),
            flags: Vec::with_capacity(range.len()),
            stats: CurvatureStats::new(self.spacing),
        };
        let mut short = 0.0f64;
        for i in range {
            let (values, flags, sh, q) = self.point(tile, index, i, s)?;
            short = short.max(sh);
            out.values.extend(values);
            out.flags.push(flags);
            out.stats.count_flags(flags);
            if let Some(q) = q {
                out.stats.residual2.add(q.rms * q.rms);
                out.stats.residual.add(q.rms);
                out.stats.max_error = out.stats.max_error.max(q.max_error);
            }
            if flags == 0 {
                let dominant = if values[0].abs() >= values[1].abs() {
                    values[0]
                } else {
                    values[1]
                };
                out.stats.dominant.add(f64::from(dominant.abs()));
            }
        }
        Ok((out, short))
    }
}

/// What produced a store's curvature column and what it measured, saved
/// beside it (`CURVATURE_META_FILE`) so `features` reuses it only when it
/// was made with the same neighbourhood.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CurvatureMeta {
    /// How the neighbourhood was chosen.
    pub hood: HoodChoice,
    /// Paper's mean spacing `d`.
    pub spacing: f64,
    /// The neighbourhood the fits used, in absolute units.
    pub resolved: CurvatureHood,
    /// Points of the store.
    pub points: u64,
    /// Points per flag bit: sparse, degenerate, ill-conditioned, unoriented.
    pub flagged: [u64; 4],
    /// RMS of the fits' residuals, and the largest `|E_j|`.
    pub rms: f64,
    /// Median of the points' RMS residuals (log-histogram bin edge).
    pub median_residual: f64,
    /// The largest `|E_j|` of any fit (the paper's residual).
    pub max_error: f64,
    /// Percentiles 0..=100 of `|k_i|` (larger-magnitude principal curvature)
    /// over the oriented points (log-histogram bin edges: at most 1.1 % high).
    pub dominant_percentiles: Vec<f64>,
}

impl CurvatureMeta {
    /// The `q`-quantile (0..1) of `|k_i|`, interpolated between percentiles.
    pub fn dominant_quantile(&self, q: f64) -> f64 {
        let p = &self.dominant_percentiles;
        if p.is_empty() {
            return 0.0;
        }
        let x = q.clamp(0.0, 1.0) * (p.len() - 1) as f64;
        let (lo, t) = (x.floor() as usize, x.fract());
        let hi = (lo + 1).min(p.len() - 1);
        p[lo] * (1.0 - t) + p[hi] * t
    }

    /// The metadata saved beside `store`'s curvature column, if any (`None` when absent or unreadable).
    pub fn load(store: &PointStore) -> Option<CurvatureMeta> {
        let text = std::fs::read_to_string(store.dir().join(CURVATURE_META_FILE)).ok()?;
        serde_json::from_str(&text).ok()
    }

    fn save(&self, store: &PointStore) -> Result<(), FeaturesError> {
        let path = store.dir().join(CURVATURE_META_FILE);
        let text = serde_json::to_string_pretty(self).map_err(|e| FeaturesError::Meta {
            path: path.clone(),
            source: Box::new(e),
        })?;
        std::fs::write(&path, text).map_err(|e| FeaturesError::Meta {
            path,
            source: Box::new(e),
        })
    }
}

/// What the curvature columns record as their making: the curvature
/// parameters, which include the normals' own.
pub(crate) fn provenance(params: &CurvatureParams) -> Provenance {
    Provenance::of("curvature", params)
}

/// The curvature pass's outcome.
#[derive(Clone, Debug)]
pub struct CurvatureReport {
    /// What the curvature column was made with and measured.
    pub meta: CurvatureMeta,
    /// Tiles processed.
    pub tiles: usize,
    /// Tiles, retries and margins of the run.
    pub run: RunStats,
    /// Whether the normals were computed first (the store had none).
    pub computed_normals: bool,
}

/// The curvature stage ([`Stage`]): its parameters, run by [`run_stage`]
/// (or [`compute_curvature`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CurvatureStage {
    /// The fit and the normals it needs.
    pub params: CurvatureParams,
}

impl StageParams for CurvatureParams {
    type Error = FeaturesError;

    fn validate(&self) -> Result<(), FeaturesError> {
        CurvatureParams::validate(self)
    }

    fn cost(&self) -> KernelCost {
        CurvatureParams::cost(self)
    }
}

impl Stage for CurvatureStage {
    const ID: StageId = StageId::CURVATURE;
    const READS: &'static [ColumnSpec] = &[NORMALS, FLAGS];
    const WRITES: &'static [ColumnSpec] = &[CURVATURE, CURVATURE_FLAGS];
    type Params = CurvatureParams;
    type Kernel = CurvatureKernel;
    type Seam<'s> = CurvatureSeam<'s>;
    type Report = CurvatureReport;
    type Error = FeaturesError;

    fn params(&self) -> &CurvatureParams {
        &self.params
    }

    fn provenance(&self) -> Provenance {
        provenance(&self.params)
    }

    /// The normals when the store has none of these parameters, the mean
    /// spacing `d`, and the neighbourhood resolved for it.
    fn kernel(
        &self,
        store: &mut PointStore,
        opts: RunOptions,
        progress: &dyn Progress,
    ) -> Result<CurvatureKernel, FeaturesError> {
        let params = &self.params;
        let computed_normals = ensure_normals(store, &params.normals, opts, progress)?.is_some();
        let estimate = ensure_spacing(store)?;
        let d = super::spacing::mean_spacing(store, estimate, opts, progress)?;
        if !(d > 0.0 && d.is_finite()) {
            return Err(FeaturesError::BadParameter(
                super::BadFeatureParameter::Coincident {
                    store: store.dir().to_path_buf(),
                    spacing: d,
                },
            ));
        }
        // The tangent-plane noise in nearest-neighbour distances, when the
        // normals pass measured it (exact sums: the same for any tiling).
        let noise_ratio = store
            .manifest()
            .sampling
            .filter(|s| s.mean_nn > 0.0)
            .map_or(0.0, |s| s.noise / s.mean_nn);
        let hood = params.hood.resolve(d, noise_ratio);
        Ok(CurvatureKernel {
            hood,
            margin: match hood {
                CurvatureHood::Radius(r) => r * 1.0001 + 1e-12,
                CurvatureHood::Knn(k) => 3.0 * estimate * (k as f64).sqrt(),
                CurvatureHood::Topological { k, .. } => 6.0 * estimate * (k as f64).sqrt(),
            },
            spacing: d,
            computed_normals,
        })
    }

    fn seam<'s>(
        &'s self,
        store: &'s PointStore,
        kernel: &CurvatureKernel,
        columns: &'s StageColumns,
    ) -> Result<CurvatureSeam<'s>, FeaturesError> {
        Ok(CurvatureSeam {
            store,
            values: columns.get(&CURVATURE)?,
            flags: columns.get(&CURVATURE_FLAGS)?,
            stats: CurvatureStats::new(kernel.spacing),
            spacing: kernel.spacing,
            hood: (self.params.hood, kernel.hood),
            computed_normals: kernel.computed_normals,
        })
    }
}

/// The curvature's seam: each tile's values and flags into their columns
/// and its statistics merged, in tile order; at the end the metadata saved
/// beside the columns ([`CurvatureMeta`]) and the report.
pub struct CurvatureSeam<'s> {
    store: &'s PointStore,
    values: &'s Column,
    flags: &'s Column,
    stats: CurvatureStats,
    /// The mean spacing `d`.
    spacing: f64,
    /// The neighbourhood as chosen and as resolved for the spacing.
    hood: (HoodChoice, CurvatureHood),
    computed_normals: bool,
}

impl Seam for CurvatureSeam<'_> {
    type Tile = CurvatureTile;
    type Report = CurvatureReport;
    type Error = FeaturesError;

    fn accept(&mut self, tile: usize, out: CurvatureTile) -> Result<(), PipelineError> {
        let start = self.store.tiles()[tile].start;
        self.values.write_f32(start, &out.values)?;
        self.flags.write_bytes(start, &out.flags)?;
        self.stats.merge(&out.stats);
        Ok(())
    }

    fn finish(
        self,
        run: RunStats,
        _: RunOptions,
        _: &dyn Progress,
    ) -> Result<CurvatureReport, FeaturesError> {
        let (store, stats) = (self.store, &self.stats);
        let meta = CurvatureMeta {
            hood: self.hood.0,
            spacing: self.spacing,
            resolved: self.hood.1,
            points: store.len(),
            flagged: stats.flagged,
            rms: stats.rms(),
            median_residual: stats.residual.quantile(0.5),
            max_error: stats.max_error,
            dominant_percentiles: (0..=100)
                .map(|p| stats.dominant.quantile(p as f64 / 100.0))
                .collect(),
        };
        meta.save(store)?;
        Ok(CurvatureReport {
            meta,
            tiles: store.tiles().len(),
            run,
            computed_normals: self.computed_normals,
        })
    }
}

/// Computes the curvature of every point of `store` into its columns,
/// computing normals first if the store has none: [`run_stage`] of
/// [`CurvatureStage`].
pub fn compute_curvature(
    store: &mut PointStore,
    params: &CurvatureParams,
    opts: RunOptions,
    progress: &dyn Progress,
) -> Result<CurvatureReport, FeaturesError> {
    run_stage(store, &CurvatureStage { params: *params }, opts, progress)
}
