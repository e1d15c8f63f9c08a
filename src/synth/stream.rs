//! Streaming front end: dispatch from a [`Shape`] to its sampler, the
//! noise, and chunked output.

use super::closed::{CapsuleSampler, CylinderSampler, MoebiusSampler, SphereSampler, TorusSampler};
use super::creased::{StepSampler, WavySampler};
use super::error::SynthError;
use super::mesh::MeshSampler;
use super::ripples::RipplesSampler;
use super::sheets::{DensityStepSampler, HolePlaneSampler, TwoSheetsSampler};
use super::terrain::TerrainSampler;
use super::{Sample, Sampler, Shape};
use crate::io::PointChunk;
use crate::rng::Rng;
use glam::DVec3;

/// Salt that separates the noise generator's seed from the surface one.
const NOISE_SALT: u64 = 0x6E6F_6973_655F_7631; // "noise_v1"

/// The validated sampler of any [`Shape`], borrowing the shape's data (a
/// mesh is never copied).
#[derive(Clone, Debug)]
pub enum ShapeSampler<'a> {
    /// Sampler of a [`Shape::Sphere`].
    Sphere(SphereSampler),
    /// Sampler of a [`Shape::Torus`].
    Torus(TorusSampler),
    /// Sampler of a [`Shape::HolePlane`].
    HolePlane(HolePlaneSampler),
    /// Sampler of a [`Shape::TwoSheets`].
    TwoSheets(TwoSheetsSampler),
    /// Sampler of a [`Shape::Terrain`].
    Terrain(TerrainSampler<'a>),
    /// Sampler of a [`Shape::Moebius`].
    Moebius(MoebiusSampler),
    /// Sampler of a [`Shape::DensityStep`].
    DensityStep(DensityStepSampler),
    /// Sampler of a [`Shape::Mesh`].
    Mesh(MeshSampler<'a>),
    /// Sampler of a [`Shape::Steps`].
    Steps(StepSampler),
    /// Sampler of a [`Shape::WavySheet`].
    Wavy(WavySampler),
    /// Sampler of a [`Shape::Cylinder`].
    Cylinder(CylinderSampler),
    /// Sampler of a [`Shape::Capsule`].
    Capsule(CapsuleSampler),
    /// Sampler of a [`Shape::Ripples`].
    Ripples(RipplesSampler),
}

impl<'a> ShapeSampler<'a> {
    /// Checks the shape's parameters once.
    pub fn new(shape: &'a Shape) -> Result<Self, SynthError> {
        Ok(match shape {
            Shape::Sphere { centre, radius } => {
                ShapeSampler::Sphere(SphereSampler::new(*centre, *radius)?)
            }
            Shape::Torus { major, minor } => {
                ShapeSampler::Torus(TorusSampler::new(*major, *minor)?)
            }
            Shape::HolePlane { side, hole_radius } => {
                ShapeSampler::HolePlane(HolePlaneSampler::new(*side, *hole_radius)?)
            }
            Shape::TwoSheets { side, separation } => {
                ShapeSampler::TwoSheets(TwoSheetsSampler::new(*side, *separation)?)
            }
            Shape::Terrain(t) => ShapeSampler::Terrain(TerrainSampler::new(t)?),
            Shape::Moebius { radius, width } => {
                ShapeSampler::Moebius(MoebiusSampler::new(*radius, *width)?)
            }
            Shape::DensityStep { side, ratio, sag } => {
                ShapeSampler::DensityStep(DensityStepSampler::new(*side, *ratio, *sag)?)
            }
            Shape::Mesh(m) => ShapeSampler::Mesh(MeshSampler::new(m)?),
            Shape::Steps(p) => ShapeSampler::Steps(StepSampler::new(p)?),
            Shape::WavySheet(w) => ShapeSampler::Wavy(WavySampler::new(*w)?),
            Shape::Cylinder { radius, length } => {
                ShapeSampler::Cylinder(CylinderSampler::new(*radius, *length)?)
            }
            Shape::Capsule { radius, length } => {
                ShapeSampler::Capsule(CapsuleSampler::new(*radius, *length)?)
            }
            Shape::Ripples {
                radius,
                amplitude,
                wavelength,
            } => ShapeSampler::Ripples(RipplesSampler::new(*radius, *amplitude, *wavelength)?),
        })
    }

    fn inner(&self) -> &dyn Sampler {
        match self {
            ShapeSampler::Sphere(s) => s,
            ShapeSampler::Torus(s) => s,
            ShapeSampler::HolePlane(s) => s,
            ShapeSampler::TwoSheets(s) => s,
            ShapeSampler::Terrain(s) => s,
            ShapeSampler::Moebius(s) => s,
            ShapeSampler::DensityStep(s) => s,
            ShapeSampler::Mesh(s) => s,
            ShapeSampler::Steps(s) => s,
            ShapeSampler::Wavy(s) => s,
            ShapeSampler::Cylinder(s) => s,
            ShapeSampler::Capsule(s) => s,
            ShapeSampler::Ripples(s) => s,
        }
    }
}

impl Sampler for ShapeSampler<'_> {
    fn sample(&self, rng: &mut Rng) -> Sample {
        self.inner().sample(rng)
    }
    fn area(&self) -> f64 {
        self.inner().area()
    }
    fn spacing_area(&self) -> f64 {
        self.inner().spacing_area()
    }
}

/// A finite, seeded stream of samples: an [`ExactSizeIterator`] plus chunk
/// fillers. Memory is O(1) in the number of samples.
#[derive(Clone, Debug)]
pub struct Stream<'a> {
    sampler: ShapeSampler<'a>,
    surface_rng: Rng,
    noise_rng: Rng,
    noise: f64,
    remaining: usize,
    emitted: u64,
}

/// `n` samples of `shape` with Gaussian position noise of standard deviation
/// `noise` per axis, fixed by `seed`.
pub fn stream(shape: &Shape, n: usize, noise: f64, seed: u64) -> Result<Stream<'_>, SynthError> {
    if !(noise.is_finite() && noise >= 0.0) {
        return Err(SynthError::BadNoise(noise));
    }
    Ok(Stream {
        sampler: ShapeSampler::new(shape)?,
        surface_rng: Rng::new(seed),
        noise_rng: Rng::new(seed ^ NOISE_SALT),
        noise,
        remaining: n,
        emitted: 0,
    })
}

impl Stream<'_> {
    /// Samples handed out so far.
    pub fn emitted(&self) -> u64 {
        self.emitted
    }

    /// Clears both vectors, then appends up to `max` samples. Returns the
    /// number written; 0 when the stream is exhausted.
    pub fn fill(&mut self, max: usize, points: &mut Vec<DVec3>, normals: &mut Vec<DVec3>) -> usize {
        points.clear();
        normals.clear();
        let count = max.min(self.remaining);
        points.reserve(count);
        normals.reserve(count);
        for s in self.by_ref().take(count) {
            points.push(s.p);
            normals.push(s.n);
        }
        count
    }

    /// Fills `chunk` like a [`crate::io::PointReader`] would: clears it, then
    /// up to `max` points with f32 normals; `first_index` counts from 0.
    pub fn fill_chunk(&mut self, chunk: &mut PointChunk, max: usize) -> usize {
        chunk.clear();
        chunk.first_index = self.emitted;
        chunk.indices = None;
        let count = max.min(self.remaining);
        let normals = chunk.normals.get_or_insert_with(Vec::new);
        chunk.xyz.reserve(count);
        normals.reserve(count);
        for s in self.by_ref().take(count) {
            chunk.xyz.push(s.p);
            normals.push(s.n.as_vec3());
        }
        count
    }
}

impl Iterator for Stream<'_> {
    type Item = Sample;

    fn next(&mut self) -> Option<Sample> {
        if self.remaining == 0 {
            return None;
        }
        self.remaining -= 1;
        self.emitted += 1;
        let mut s = self.sampler.sample(&mut self.surface_rng);
        if self.noise > 0.0 {
            s.p += self.noise_rng.gaussian_vector(self.noise);
        }
        Some(s)
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        (self.remaining, Some(self.remaining))
    }
}

impl ExactSizeIterator for Stream<'_> {}
