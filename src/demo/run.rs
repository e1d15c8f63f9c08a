//! The demo's steps, each returning what the caller prints: the sample,
//! its reconstruction (in a scratch store beside the mesh, removed after),
//! the mesh's checks against the dragon, and its picture.

use super::{dragon_scan, DemoError};
use crate::io::memory::MemoryReader;
use crate::memory::KernelCost;
use crate::mesh::distance::{compare, DistanceReport, Reference};
use crate::mesh::{angle_report, quality, self_intersections, Mesh, MeshFormat};
use crate::normals::evaluate::{accuracy, normals_in_input_order, NormalAccuracy};
use crate::pipeline::RunSettings;
use crate::progress::Progress;
use crate::recon::implicit::reconstruct::{reconstruct_implicit, ImplicitParams, ImplicitReport};
use crate::recon::projection::{reconstruct_projection, ProjectionParams, ProjectionReport};
use crate::render::scene::{Scene, Style};
use crate::store::{build::scratch_store_dir, build_store, PointStore};
use crate::synth::{Scan, TriMesh};
use std::fmt;
use std::path::Path;

/// What the demo closes with.
pub const NEXT_STEPS: &str = "demo: next, on a scan of your own: `scanmesh info scan.las`, then `scanmesh reconstruct scan.las -o mesh.ply` (open surface) or `--closed`, `scanmesh render --mesh mesh.ply -o mesh.png`; `scanmesh --help` lists every command";

/// How the demo reconstructs the sample.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum DemoMethod {
    /// Signed distance + marching cubes (paper 1), closed: the dragon is a
    /// closed object, and the watertight mode is its best mesh.
    #[value(help = "Signed distance + marching cubes (paper 1)")]
    Implicit,
    /// Local-projection triangulation of the points (paper 2).
    Projection,
}

/// Points sampled from the embedded dragon with noise of 0.1 spacings.
pub struct DemoSample {
    /// The points and their true normals.
    pub scan: Scan,
    /// The dragon they were sampled from.
    pub dragon: TriMesh,
    /// The sample's mean nearest-neighbour distance.
    pub spacing: f64,
}

impl DemoSample {
    /// `n` points of the dragon (seed 1).
    pub fn new(n: usize) -> Result<Self, DemoError> {
        let (scan, dragon, spacing) = dragon_scan(n, 0.1, 1)?;
        Ok(DemoSample {
            scan,
            dragon,
            spacing,
        })
    }
}

impl fmt::Display for DemoSample {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "demo: {} points sampled from the embedded Stanford dragon ({} triangles), noise 0.1 x spacing ({:.3e})",
            self.scan.len(),
            self.dragon.faces.len(),
            self.spacing
        )
    }
}

/// What the demo's reconstruction did.
pub enum DemoMesh {
    /// The implicit surface's report, and its normals against the
    /// dragon's faces.
    Implicit(ImplicitReport, NormalAccuracy),
    /// The projection's report.
    Projection(ProjectionReport),
}

impl DemoMethod {
    fn implicit() -> ImplicitParams {
        ImplicitParams {
            closed: true,
            ..ImplicitParams::default()
        }
    }

    /// What a run of this method costs (to check the promise first).
    pub fn cost(self) -> KernelCost {
        match self {
            DemoMethod::Implicit => Self::implicit().cost(),
            DemoMethod::Projection => ProjectionParams::default().cost(),
        }
    }

    /// Reconstructs `sample` into a binary PLY at `output` within
    /// `settings`' promise, in a scratch store beside it.
    pub fn reconstruct(
        self,
        sample: &DemoSample,
        settings: &RunSettings,
        output: &Path,
        progress: &dyn Progress,
    ) -> Result<DemoMesh, DemoError> {
        let dir = scratch_store_dir(output);
        let mut reader =
            MemoryReader::new("embedded dragon sample", sample.scan.points.clone(), None);
        let opts = settings.build_options(self.cost());
        let result = build_store(&mut reader, &dir, &opts, progress)
            .map_err(DemoError::from)
            .and_then(|mut store| self.in_store(&mut store, sample, settings, output, progress));
        let _ = std::fs::remove_dir_all(&dir);
        result
    }

    fn in_store(
        self,
        store: &mut PointStore,
        sample: &DemoSample,
        settings: &RunSettings,
        output: &Path,
        progress: &dyn Progress,
    ) -> Result<DemoMesh, DemoError> {
        let (_, run) = settings.plan_for(store, self.cost())?;
        let ply = MeshFormat::PlyBinary;
        Ok(match self {
            DemoMethod::Projection => {
                let params = ProjectionParams::default();
                DemoMesh::Projection(reconstruct_projection(
                    store, &params, output, ply, run, progress,
                )?)
            }
            DemoMethod::Implicit => {
                let params = Self::implicit();
                let r = reconstruct_implicit(store, &params, output, ply, run, progress)?;
                let normals = accuracy(&normals_in_input_order(store)?, &sample.scan.normals);
                DemoMesh::Implicit(r, normals)
            }
        })
    }
}

/// The normals' line of the implicit demo.
pub fn normals_line(acc: &NormalAccuracy) -> String {
    format!(
        "demo: normals vs the dragon's faces: median angle {:.2} deg, {:.2} % oriented outward",
        acc.median_angle_deg,
        100.0 * acc.oriented_fraction
    )
}

/// The mesh the demo wrote, checked: its quality, angles and
/// self-intersections, and its distance to the dragon.
pub struct DemoCheck {
    /// The mesh as written.
    pub mesh: Mesh,
    /// Quality, angle and self-intersection reports, one line each.
    pub checks: [String; 3],
    /// Distances both ways between the mesh and the dragon.
    pub distance: DistanceReport,
    /// The sample's spacing, the distances' unit.
    pub spacing: f64,
}

impl DemoCheck {
    /// Reads the mesh at `output` and measures it against `sample`'s dragon.
    pub fn of(output: &Path, sample: &DemoSample) -> Result<Self, DemoError> {
        let (v, t) = crate::io::read_mesh_any(output)?;
        let mesh = Mesh::new(v, t);
        let checks = [
            quality(&mesh).to_string(),
            angle_report(&mesh).to_string(),
            self_intersections(&mesh).to_string(),
        ];
        let truth = Mesh::new(sample.dragon.vertices.clone(), sample.dragon.faces.clone());
        let distance = compare(&mesh, Reference::Mesh(&truth));
        Ok(DemoCheck {
            mesh,
            checks,
            distance,
            spacing: sample.spacing,
        })
    }

    /// The distance line, when both ways were measured. One unit
    /// throughout: sp, the sample's mean nearest-neighbour distance
    /// (`eval`'s own report uses the reference's, a different number for
    /// the same distance).
    pub fn distance_line(&self) -> Option<String> {
        let d = &self.distance;
        let (there, back, h) = (
            d.mesh_to_reference.absolute?,
            d.reference_to_mesh.absolute?,
            d.hausdorff?,
        );
        let spacing = self.spacing;
        Some(format!(
            "demo: distance to the dragon in sp (the sample's mean nearest-neighbour distance, {spacing:.3e}): mean {:.3} sp (mesh to dragon {:.3}, dragon to mesh {:.3}), Hausdorff {:.2} sp",
            0.5 * (there.mean + back.mean) / spacing,
            there.mean / spacing,
            back.mean / spacing,
            h / spacing
        ))
    }
}

/// Draws `mesh` seen from the front (the dragon's +z side, y up) into a
/// PNG at `path`; returns the line that says so.
pub fn picture(mesh: &Mesh, path: &Path) -> Result<String, DemoError> {
    let scene = Scene {
        mesh: Some((mesh.vertices.clone(), mesh.triangles.clone())),
        ..Scene::default()
    };
    let style = Style {
        width: 1200,
        height: 900,
        forward: glam::DVec3::new(0.0, 0.0, -1.0),
        up: glam::DVec3::Y,
        point_radius: 1.0,
        line_width: 2.0,
    };
    let canvas = scene.draw(&style).ok_or(DemoError::NothingToDraw)?;
    canvas.write_png(path)?;
    Ok(format!("demo: picture of the mesh -> {}", path.display()))
}
