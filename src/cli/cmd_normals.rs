//! `scanmesh normals`: oriented normals for every point, in input order.

use super::HoodKind;
use anyhow::{bail, Context, Result};
use clap::{Args, ValueEnum};
use glam::DVec3;
use scanmesh::io::{AttributeSet, Carried, WriterSpec};
use scanmesh::normals::{
    compute_normals, EdgeCost, NormalHood, NormalParams, NormalsReport, Orientation, Sensor,
};
use scanmesh::spatial::KnnBackend;
use scanmesh::store::{export_points_keeping, StageId, NORMALS};
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(Args)]
pub struct NormalsArgs {
    /// Input point file or store directory.
    pub input: PathBuf,
    /// Output point file: .ply (binary; --ascii for text), .xyz, .csv,
    /// .las, .laz or .pcd, normals as that format keeps them.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Neighbours per point (paper: 8..15).
    #[arg(long, default_value_t = 12)]
    k: usize,
    /// kNN structure.
    #[arg(long, value_enum, default_value_t = Knn::Grid)]
    knn: Knn,
    #[command(flatten)]
    hood: HoodArgs,
    /// How normals get their sign. `auto` (default): toward each scan's
    /// station when the input names them (E57 poses), up for aerial data
    /// (a LAS/LAZ wider than tall, or --sensor aerial) with the spanning
    /// tree past vertical, else the spanning tree.
    #[arg(long, value_enum, default_value_t = Orient::Auto)]
    orient: Orient,
    /// What took the scan, a hint to --orient auto: `aerial` (normals face
    /// up), `terrestrial` (never taken for aerial), `auto` (judge from the
    /// data).
    #[arg(long, value_enum, default_value_t = SensorArg::Auto)]
    sensor: SensorArg,
    /// Spanning-tree edge cost: `offset` (default) adds the tangent-plane
    /// offset to the paper's `1 - |ni.nj|` so the tree does not cross thin parts
    /// (for --orient sources|single-source: subtracts it from `w`).
    #[arg(long, value_enum, default_value_t = Cost::Offset)]
    cost: Cost,
    /// Scanner position x,y,z (implies --orient viewpoint).
    #[arg(long, value_parser = parse_point)]
    viewpoint: Option<DVec3>,
    /// Source propagation threshold on |ni.nj| (--orient sources|single-source).
    #[arg(long, default_value_t = scanmesh::normals::sources::DEFAULT_TAU)]
    tau: f64,
    /// Direction x,y,z of the single source (--orient single-source).
    #[arg(long, value_parser = parse_point, default_value = "0,0,1")]
    source_direction: DVec3,
    /// Write PLY as ASCII instead of binary.
    #[arg(long)]
    ascii: bool,
    #[command(flatten)]
    pub common: super::CommonArgs,
    #[command(flatten)]
    pub run: super::RunDirArgs,
}

/// The tangent planes' neighbourhood (shared with `reconstruct`).
#[derive(Args)]
pub struct HoodArgs {
    /// Neighbourhood of the tangent planes and the spanning tree: the k
    /// nearest (paper 1), or the topological neighbours of paper 3 (mean
    /// reverse shift, k per query), which add the sparse side of a density
    /// change that the k nearest miss.
    #[arg(long, visible_alias = "neighbors", value_enum, default_value_t = HoodKind::Knn)]
    neighbours: HoodKind,
    /// Cap on reverse-shift iterations (--neighbours topological).
    #[arg(long, default_value_t = 10)]
    max_iterations: usize,
}

impl HoodArgs {
    pub fn hood(&self) -> NormalHood {
        match self.neighbours {
            HoodKind::Knn => NormalHood::Knn,
            HoodKind::Topological => NormalHood::Topological {
                max_iterations: self.max_iterations,
            },
        }
    }
}

#[derive(Clone, Copy, ValueEnum)]
enum Knn {
    Grid,
    Kdtree,
}

#[derive(Clone, Copy, ValueEnum)]
enum Cost {
    /// The paper's 1 - |ni.nj|.
    Paper,
    /// Paper cost plus the edge's tangent-plane offset.
    Offset,
}

#[derive(Clone, Copy, ValueEnum, PartialEq)]
enum SensorArg {
    /// Judge from the data.
    Auto,
    /// Airborne lidar.
    Aerial,
    /// Ground-based scanner, or an object.
    Terrestrial,
}

#[derive(Clone, Copy, ValueEnum, PartialEq)]
enum Orient {
    /// From what the scan knows: stations, up (aerial), else the spanning tree.
    Auto,
    /// Minimum spanning tree over the Riemannian graph (paper 1).
    Mst,
    /// Up (+z), the spanning tree where a surface turns past vertical (aerial).
    Aerial,
    /// Toward each point's own scan station (E57 scan poses).
    Stations,
    /// Toward --viewpoint.
    Viewpoint,
    /// Six sources at the extreme points along +-X, +-Y, +-Z (paper 5).
    Sources,
    /// One source, the point farthest along --source-direction (terrain).
    SingleSource,
    /// Unoriented (canonical PCA sign).
    None,
}

fn parse_point(s: &str) -> Result<DVec3, String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|t| t.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|e| format!("expected x,y,z: {e}"))?;
    match v.as_slice() {
        [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok(DVec3::new(*x, *y, *z)),
        _ => Err("expected three finite numbers x,y,z".into()),
    }
}

impl NormalsArgs {
    fn params(&self) -> Result<NormalParams> {
        if self.sensor != SensorArg::Auto && self.orient != Orient::Auto {
            bail!("--sensor goes with --orient auto only");
        }
        let orientation = match (self.orient, self.viewpoint) {
            (Orient::Viewpoint, None) => bail!("--orient viewpoint needs --viewpoint x,y,z"),
            (Orient::Auto | Orient::Viewpoint, Some(v)) => Orientation::Viewpoint(v),
            (Orient::Auto, None) => Orientation::Auto(match self.sensor {
                SensorArg::Auto => Sensor::Auto,
                SensorArg::Aerial => Sensor::Aerial,
                SensorArg::Terrestrial => Sensor::Terrestrial,
            }),
            (Orient::Mst, None) => Orientation::SpanningTree,
            (Orient::Aerial, None) => Orientation::Aerial,
            (Orient::Stations, None) => Orientation::Stations,
            (Orient::None, _) => Orientation::None,
            (
                Orient::Mst
                | Orient::Aerial
                | Orient::Stations
                | Orient::Sources
                | Orient::SingleSource,
                Some(_),
            ) => {
                bail!("--viewpoint goes with --orient viewpoint only")
            }
            (Orient::Sources, None) => Orientation::SixSources { tau: self.tau },
            (Orient::SingleSource, None) => Orientation::SingleSource {
                direction: self.source_direction,
                tau: self.tau,
            },
        };
        if !(0.0..=1.0).contains(&self.tau) {
            bail!("--tau must lie in [0, 1]");
        }
        if self.source_direction.try_normalize().is_none() {
            bail!("--source-direction must be non-zero");
        }
        Ok(NormalParams {
            k: self.k,
            backend: match self.knn {
                Knn::Grid => KnnBackend::Grid,
                Knn::Kdtree => KnnBackend::KdTree,
            },
            neighbourhood: self.hood.hood(),
            orientation,
            cost: match self.cost {
                Cost::Paper => EdgeCost::Paper,
                Cost::Offset => EdgeCost::TangentOffset,
            },
        })
    }
}

pub fn run(a: NormalsArgs) -> Result<()> {
    let s = a.common.settings_in(&a.run)?;
    let params = a.params()?;
    params.validate()?;
    s.init_threads();
    super::check_distinct(&a.input, &a.output)?;
    let mut spec = output_spec(&a.output, a.ascii)?;
    let progress = super::progress::progress(s.quiet);
    let t0 = Instant::now();
    let mut run = s.open_input(&a.input, &a.output, params.cost(), progress.as_ref())?;
    let store = &mut run.ws.store;
    // A resumed run keeps normals it finished (its store outlives it).
    let kept = match &s.run {
        Some(r) => r.run().stage::<NormalsReport>(StageId::Normals)?,
        None => None,
    };
    let report = match kept {
        Some(report) if store.has_column(&NORMALS) => report,
        _ => {
            let report = compute_normals(store, &params, run.opts, progress.as_ref())?;
            if let Some(r) = &s.run {
                r.run().keep_stage(StageId::Normals, &report)?;
            }
            report
        }
    };
    spec.attributes = carried_attributes(store.attributes(), &spec, &a.output, s.quiet);
    let window = run.plan.window_points;
    let read = s.read_options();
    let keep = s.keep_unselected.then_some((a.input.as_path(), &read));
    export_points_keeping(store, &a.output, &spec, window, keep, progress.as_ref())
        .with_context(|| format!("writing {}", a.output.display()))?;
    super::report::unselected_kept(s.keep_unselected);
    print_summary(&report, t0.elapsed().as_secs_f64(), &a.output);
    Ok(())
}

/// The normals' output: every format of the table that holds normals,
/// with flags where it holds them.
pub fn output_spec(path: &Path, ascii: bool) -> Result<WriterSpec> {
    let carried = Carried {
        normals: true,
        flags: true,
        ..Carried::default()
    };
    Ok(scanmesh::io::output_spec(path, &carried, ascii)?)
}

/// The input's attributes that `output`'s format can hold; says which it
/// cannot (unless `quiet`).
pub fn carried_attributes(
    input: AttributeSet,
    spec: &WriterSpec,
    output: &Path,
    quiet: bool,
) -> AttributeSet {
    let carried = input.intersect(spec.format.attributes());
    let dropped = input.without(carried);
    if !dropped.is_empty() && !quiet {
        eprintln!(
            "note: {} cannot hold the input's {}: not written",
            output.display(),
            dropped.describe()
        );
    }
    carried
}

pub fn print_summary(r: &NormalsReport, secs: f64, out: &Path) {
    super::report::summary(format!(
        "normals: {} points, {} tiles ({} reloaded with a wider margin), {} degenerate, {} unoriented, {}, oriented by {}, {} components, {:.2} s, peak {} -> {}",
        r.points,
        r.tiles,
        r.run.retries,
        r.degenerate,
        r.unoriented,
        evidence_summary(r),
        r.oriented_by.describe(),
        r.components,
        secs,
        super::peak(),
        out.display()
    ));
}

/// How many normals disagree with the scan's own evidence, for the
/// summary: "0 unoriented" must not read as "all right" when they face
/// the wrong way.
pub fn evidence_summary(r: &NormalsReport) -> String {
    match r.evidence {
        Some(e) => format!(
            "{} of {} checked {} ({:.2} %)",
            e.against,
            e.checked,
            e.evidence.describe(),
            if e.checked > 0 {
                100.0 * e.against as f64 / e.checked as f64
            } else {
                0.0
            }
        ),
        None => "no orientation evidence in the input (no station, not aerial)".into(),
    }
}
