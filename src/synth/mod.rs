//! Seeded synthetic scans of surfaces with known truth (position and normal),
//! for tests and benches: sphere, torus, plane with a hole, two close sheets,
//! terrain with buildings, Moebius strip, an open cylinder, a capsule, a
//! 20:1 density step, any triangle mesh, and shapes with known feature lines
//! (stepped prisms, a wavy sheet: `creased`; concentric ripples: `ripples`).
//!
//! Everything streams: [`stream`] yields one [`Sample`] at a time (or fills
//! bounded chunks), so 10^7 points never need to be in memory at once;
//! [`generate`] collects a small scan. Output is a pure function of
//! `(shape, n, noise, seed)`, bit-identical across platforms (see `rng`).
//!
//! Noise is isotropic Gaussian on positions (truth normals unchanged), drawn
//! from a second generator so that the noise-free scan with the same seed
//! holds the exact surface points of the noisy one.

mod closed;
mod creased;
mod error;
pub mod fibonacci;
mod mesh;
mod ripples;
mod sheets;
mod stations;
mod stream;
mod terrain;

pub use crate::geom::LineKind;
pub use crate::rng::Rng;
pub use creased::{StepProfile, TrueSegment, WavySheet};
pub use error::SynthError;
pub use fibonacci::{fibonacci_direction, fibonacci_sphere};
pub use mesh::TriMesh;
pub use stations::{scan_from_stations, Stations};
pub use stream::{stream, ShapeSampler, Stream};
pub use terrain::{Building, Terrain};

use glam::DVec3;
use ripples::RipplesSampler;

/// One synthetic point: position (noisy if noise was asked for) and the true
/// unit normal of the surface point it was drawn from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// The point (noisy if noise was asked for).
    pub p: DVec3,
    /// Outward where the surface is orientable.
    pub n: DVec3,
}

/// A noise-free point source on one surface.
pub(crate) trait Sampler {
    /// One point, distributed by the surface's sampling density.
    fn sample(&self, rng: &mut Rng) -> Sample;
    /// Total surface area.
    fn area(&self) -> f64;
    /// `(integral sqrt(f) dA)^2`, with `f` the sampling density per unit area
    /// (a probability density over the surface). Equals the area for uniform
    /// sampling and is smaller otherwise; it sets the mean spacing.
    fn spacing_area(&self) -> f64 {
        self.area()
    }
}

/// The surfaces with known truth. Squares are centred at the origin in the
/// xy-plane.
#[derive(Clone, Debug, PartialEq)]
pub enum Shape {
    /// Sphere of `radius` around `centre`.
    Sphere {
        /// Centre of the sphere.
        centre: DVec3,
        /// Radius of the sphere.
        radius: f64,
    },
    /// Ring torus around the z axis, `minor < major`.
    Torus {
        /// Radius of the centre circle.
        major: f64,
        /// Radius of the tube.
        minor: f64,
    },
    /// Square plane `z = 0` with a centred circular hole.
    HolePlane {
        /// Side of the square.
        side: f64,
        /// Radius of the hole.
        hole_radius: f64,
    },
    /// Squares at `z = +-separation/2`, normals `+-z`.
    TwoSheets {
        /// Side of each square.
        side: f64,
        /// Distance between the sheets along z.
        separation: f64,
    },
    /// Hilly ground with box buildings (see [`Terrain`]).
    Terrain(Terrain),
    /// Centre-line radius and strip width, `width < radius`.
    Moebius {
        /// Radius of the centre line.
        radius: f64,
        /// Width of the strip.
        width: f64,
    },
    /// `z = sag (2x/side)^2`; density on `x < 0` is `ratio` x that on `x >= 0`.
    DensityStep {
        /// Side of the square.
        side: f64,
        /// Density on `x < 0` over density on `x >= 0`.
        ratio: f64,
        /// Height of the parabola at the square's edges.
        sag: f64,
    },
    /// Area-uniform samples of a triangle mesh.
    Mesh(TriMesh),
    /// A step profile extruded into a closed prism (known creases).
    Steps(StepProfile),
    /// A sinusoidal sheet (known crest and trough lines).
    WavySheet(WavySheet),
    /// Open tube (no caps) around the z axis, `|z| <= length/2`.
    Cylinder {
        /// Radius of the tube.
        radius: f64,
        /// Extent along z.
        length: f64,
    },
    /// Closed capsule around the z axis: a tube of `length` closed by
    /// hemispheres of its radius.
    Capsule {
        /// Radius of the tube and of the caps.
        radius: f64,
        /// Length of the straight part along z (the caps excluded).
        length: f64,
    },
    /// Disc of `radius` with `z = amplitude sin(2 pi rho / wavelength)`,
    /// normals up (known circular crest and trough lines).
    Ripples {
        /// Radius of the disc in (x, y).
        radius: f64,
        /// Height of the crests above z = 0.
        amplitude: f64,
        /// Distance between crests along the radius.
        wavelength: f64,
    },
}

impl Shape {
    /// Sphere of `radius` around `centre`.
    pub fn sphere(centre: DVec3, radius: f64) -> Self {
        Shape::Sphere { centre, radius }
    }
    /// Sphere of radius 1 around the origin.
    pub fn unit_sphere() -> Self {
        Shape::sphere(DVec3::ZERO, 1.0)
    }
    /// Ring torus of centre-circle radius `major` and tube radius `minor`.
    pub fn torus(major: f64, minor: f64) -> Self {
        Shape::Torus { major, minor }
    }
    /// Square plane of `side` with a centred hole of `hole_radius`.
    pub fn hole_plane(side: f64, hole_radius: f64) -> Self {
        Shape::HolePlane { side, hole_radius }
    }
    /// Two parallel squares of `side`, `separation` apart along z.
    pub fn two_sheets(side: f64, separation: f64) -> Self {
        Shape::TwoSheets { side, separation }
    }
    /// The default city scene ([`Terrain::city`]).
    pub fn terrain() -> Self {
        Shape::Terrain(Terrain::city())
    }
    /// Moebius strip of centre-line `radius` and strip `width`.
    pub fn moebius(radius: f64, width: f64) -> Self {
        Shape::Moebius { radius, width }
    }
    /// Density step with a sag of 5 % of the side.
    pub fn density_step(side: f64, ratio: f64) -> Self {
        Shape::DensityStep {
            side,
            ratio,
            sag: 0.05 * side,
        }
    }
    /// Area-uniform samples of `mesh`.
    pub fn mesh(mesh: TriMesh) -> Self {
        Shape::Mesh(mesh)
    }
    /// Open tube of `radius` and `length` around the z axis.
    pub fn cylinder(radius: f64, length: f64) -> Self {
        Shape::Cylinder { radius, length }
    }
    /// Capsule of `radius` with a straight part of `length` around the z axis.
    pub fn capsule(radius: f64, length: f64) -> Self {
        Shape::Capsule { radius, length }
    }
    /// Concentric ripples of `amplitude` and `wavelength` on a disc of
    /// `radius`.
    pub fn ripples(radius: f64, amplitude: f64, wavelength: f64) -> Self {
        Shape::Ripples {
            radius,
            amplitude,
            wavelength,
        }
    }

    /// Short kebab-case name of the kind of shape.
    pub fn name(&self) -> &'static str {
        match self {
            Shape::Sphere { .. } => "sphere",
            Shape::Torus { .. } => "torus",
            Shape::HolePlane { .. } => "hole-plane",
            Shape::TwoSheets { .. } => "two-sheets",
            Shape::Terrain(_) => "terrain",
            Shape::Moebius { .. } => "moebius",
            Shape::DensityStep { .. } => "density-step",
            Shape::Mesh(_) => "mesh",
            Shape::Steps(_) => "steps",
            Shape::WavySheet(_) => "wavy-sheet",
            Shape::Cylinder { .. } => "cylinder",
            Shape::Capsule { .. } => "capsule",
            Shape::Ripples { .. } => "ripples",
        }
    }

    /// One instance of every kind with sensible parameters (the
    /// mesh is a unit icosahedron). Unit-scale except the terrain (100 m).
    pub fn presets() -> Vec<Shape> {
        vec![
            Shape::unit_sphere(),
            Shape::torus(1.0, 0.3),
            Shape::hole_plane(2.0, 0.4),
            Shape::two_sheets(1.0, 0.02),
            Shape::terrain(),
            Shape::moebius(1.0, 0.5),
            Shape::density_step(2.0, 20.0),
            Shape::mesh(TriMesh::icosahedron(1.0)),
            Shape::Steps(StepProfile::stepped_block()),
            Shape::wavy_sheet(),
            Shape::cylinder(0.3, 2.0),
            Shape::capsule(0.3, 1.0),
            Shape::ripples_preset(),
        ]
    }

    /// A 4 x 4 sheet with crests and troughs every 0.35 (amplitude 0.07:
    /// slopes up to 52 degrees, crest radius of curvature 0.044, about 6
    /// mean spacings at 100,000 points).
    pub fn wavy_sheet() -> Self {
        Shape::WavySheet(WavySheet {
            side: 4.0,
            amplitude: 0.07,
            wavelength: 0.35,
        })
    }

    /// Ripples on a disc of radius 2 with crests every 0.35 (amplitude
    /// 0.0875: slopes up to 57 degrees, crest radius of curvature 0.035,
    /// about 5 mean spacings at 100,000 points).
    pub fn ripples_preset() -> Self {
        Shape::ripples(2.0, 0.0875, 0.35)
    }

    /// The true feature lines of the shapes that have them (ridges convex
    /// seen from the normals' side, valleys concave). `None` for ripples
    /// whose parameters are invalid.
    pub fn feature_lines(&self) -> Option<Vec<TrueSegment>> {
        match self {
            Shape::Steps(p) => Some(p.truth()),
            Shape::WavySheet(w) => Some(w.truth()),
            Shape::Ripples {
                radius,
                amplitude,
                wavelength,
            } => RipplesSampler::new(*radius, *amplitude, *wavelength)
                .ok()
                .map(|s| s.truth()),
            _ => None,
        }
    }

    /// The preset of kind `name` (see [`Shape::presets`]).
    pub fn preset(name: &str) -> Option<Shape> {
        // Two presets of the step kind, by their own names.
        match name {
            "stepped-block" => return Some(Shape::Steps(StepProfile::stepped_block())),
            "notched-box" => return Some(Shape::Steps(StepProfile::notched_box())),
            _ => {}
        }
        Shape::presets().into_iter().find(|s| s.name() == name)
    }
}

/// A collected scan: `points[i]` has true normal `normals[i]`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Scan {
    /// The sampled points.
    pub points: Vec<DVec3>,
    /// The true unit normal at each point.
    pub normals: Vec<DVec3>,
}

impl Scan {
    /// Points in the scan.
    pub fn len(&self) -> usize {
        self.points.len()
    }
    /// Whether the scan has no point.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }
}

/// `n` samples of `shape` in memory (for small `n`; use [`stream`] for
/// large ones). The same as collecting `stream(shape, n, noise, seed)`.
pub fn generate(shape: &Shape, n: usize, noise: f64, seed: u64) -> Result<Scan, SynthError> {
    let mut s = stream(shape, n, noise, seed)?;
    let mut scan = Scan::default();
    s.fill(n, &mut scan.points, &mut scan.normals);
    Ok(scan)
}

/// Expected mean nearest-neighbour spacing of `n` samples of `shape`:
/// `0.5 * sqrt(spacing_area / n)`, the planar Poisson value
/// `1 / (2 sqrt(lambda))` integrated over the density (Clark & Evans 1954).
/// Boundaries make real spacings a little larger, and it ignores neighbours
/// across a thin gap (two sheets). Infinite for `n == 0`.
pub fn mean_spacing_hint(shape: &Shape, n: usize) -> Result<f64, SynthError> {
    let sampler = ShapeSampler::new(shape)?;
    if n == 0 {
        return Ok(f64::INFINITY);
    }
    Ok(0.5 * (sampler.spacing_area() / n as f64).sqrt())
}
