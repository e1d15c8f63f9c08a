//! Open sheets: a square plane with a circular hole, two close parallel
//! sheets (a thin slab), and a gently curved sheet whose sampling density
//! steps 20:1 across `x = 0` (the non-uniform input of the mean reverse shift
//! paper, `papers/README.md` section 3).
//!
//! All squares are centred at the origin with sides along x and y.

use super::error::{finite, positive, require, SynthError};
use super::{Sample, Sampler};
use crate::rng::Rng;
use glam::DVec3;
use std::f64::consts::PI;

/// Plane `z = 0` over `[-side/2, side/2]^2` minus the disc
/// `x^2 + y^2 < hole_radius^2`; normals `+z`. Two boundary loops.
#[derive(Clone, Debug)]
pub struct HolePlaneSampler {
    half: f64,
    hole_radius: f64,
}

impl HolePlaneSampler {
    pub fn new(side: f64, hole_radius: f64) -> Result<Self, SynthError> {
        let half = positive("hole-plane", "side", side)? * 0.5;
        let hole_radius = positive("hole-plane", "hole_radius", hole_radius)?;
        require(
            hole_radius < half,
            "hole-plane",
            "hole_radius",
            hole_radius,
            "must be < side / 2 (hole inside the square)",
        )?;
        Ok(HolePlaneSampler { half, hole_radius })
    }
}

impl Sampler for HolePlaneSampler {
    fn sample(&self, rng: &mut Rng) -> Sample {
        loop {
            let x = rng.range(-self.half, self.half);
            let y = rng.range(-self.half, self.half);
            if x * x + y * y >= self.hole_radius * self.hole_radius {
                return Sample {
                    p: DVec3::new(x, y, 0.0),
                    n: DVec3::Z,
                };
            }
        }
    }
    fn area(&self) -> f64 {
        4.0 * self.half * self.half - PI * self.hole_radius * self.hole_radius
    }
}

/// Two squares at `z = +separation/2` (normal `+z`) and `z = -separation/2`
/// (normal `-z`): the outward normals of a thin slab without its rim.
/// Each sample picks a sheet with probability 1/2.
#[derive(Clone, Debug)]
pub struct TwoSheetsSampler {
    half: f64,
    half_gap: f64,
}

impl TwoSheetsSampler {
    pub fn new(side: f64, separation: f64) -> Result<Self, SynthError> {
        let half = positive("two-sheets", "side", side)? * 0.5;
        let half_gap = positive("two-sheets", "separation", separation)? * 0.5;
        Ok(TwoSheetsSampler { half, half_gap })
    }
}

impl Sampler for TwoSheetsSampler {
    fn sample(&self, rng: &mut Rng) -> Sample {
        let upper = rng.next_u64() >> 63 == 1;
        let x = rng.range(-self.half, self.half);
        let y = rng.range(-self.half, self.half);
        let sign = if upper { 1.0 } else { -1.0 };
        Sample {
            p: DVec3::new(x, y, sign * self.half_gap),
            n: DVec3::new(0.0, 0.0, sign),
        }
    }
    fn area(&self) -> f64 {
        8.0 * self.half * self.half
    }
}

/// Sheet `z = sag * (2x / side)^2` over `[-side/2, side/2]^2`, normals
/// upward; the density per unit area on `x < 0` is `ratio` times that on
/// `x >= 0`.
///
/// The surface is symmetric in x, so both halves have the same area: a
/// sample picks the dense half with probability `ratio / (ratio + 1)`, then
/// is uniform by area within it (rejection on the slope factor).
#[derive(Clone, Debug)]
pub struct DensityStepSampler {
    half: f64,
    sag: f64,
    ratio: f64,
}

impl DensityStepSampler {
    pub fn new(side: f64, ratio: f64, sag: f64) -> Result<Self, SynthError> {
        let half = positive("density-step", "side", side)? * 0.5;
        let ratio = positive("density-step", "ratio", ratio)?;
        require(ratio >= 1.0, "density-step", "ratio", ratio, "must be >= 1")?;
        let sag = finite("density-step", "sag", sag)?;
        Ok(DensityStepSampler { half, sag, ratio })
    }

    /// Height and its x-derivative at `x`.
    pub fn height(&self, x: f64) -> (f64, f64) {
        let k = self.sag / (self.half * self.half);
        (k * x * x, 2.0 * k * x)
    }

    fn slope_factor(&self, x: f64) -> f64 {
        let (_, zx) = self.height(x);
        (1.0 + zx * zx).sqrt()
    }

    /// Area of one half (the same for both): closed form of
    /// `side * integral_0^{side/2} sqrt(1 + (2 k x)^2) dx`.
    fn half_area(&self) -> f64 {
        let side = 2.0 * self.half;
        let a = 2.0 * self.sag / (self.half * self.half);
        if a == 0.0 {
            return side * self.half;
        }
        let s = a * self.half;
        let root = (1.0 + s * s).sqrt();
        side * (s * root + (s + root).ln()) / (2.0 * a)
    }
}

impl Sampler for DensityStepSampler {
    fn sample(&self, rng: &mut Rng) -> Sample {
        let dense = rng.uniform() * (self.ratio + 1.0) < self.ratio;
        let bound = self.slope_factor(self.half);
        loop {
            let u = rng.range(0.0, self.half);
            let x = if dense { -u } else { u };
            let y = rng.range(-self.half, self.half);
            if rng.uniform() * bound < self.slope_factor(x) {
                let (z, zx) = self.height(x);
                let n = DVec3::new(-zx, 0.0, 1.0);
                return Sample {
                    p: DVec3::new(x, y, z),
                    n: n / n.length(),
                };
            }
        }
    }
    fn area(&self) -> f64 {
        2.0 * self.half_area()
    }
    /// `(integral sqrt(f) dA)^2` for the two-level density: each half has
    /// area `A/2` and probability `p_i`, so it is `A/2 (sqrt(p1) + sqrt(p2))^2`.
    fn spacing_area(&self) -> f64 {
        let p_dense = self.ratio / (self.ratio + 1.0);
        let root_sum = p_dense.sqrt() + (1.0 - p_dense).sqrt();
        self.half_area() * root_sum * root_sum
    }
}
