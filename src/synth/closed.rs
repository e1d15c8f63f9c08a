//! Parametric surfaces sampled uniformly by area: sphere, torus and the
//! (non-orientable) Moebius strip.
//!
//! Uniform-by-area sampling of a parametrised surface: draw parameters
//! uniformly and accept with probability `|x_u x x_v| / max |x_u x x_v|`
//! (rejection sampling, e.g. Williamson 1987, "Random selection of points
//! distributed on curved surfaces"). Angles come from [`Rng::unit_circle`],
//! so no trigonometric function (and no platform `libm`) is involved.

use super::error::{positive, require, SynthError};
use super::rng::Rng;
use super::{Sample, Sampler};
use glam::DVec3;
use std::f64::consts::PI;

/// Sphere: `|p - centre| = radius`, outward normals.
#[derive(Clone, Debug)]
pub struct SphereSampler {
    centre: DVec3,
    radius: f64,
}

impl SphereSampler {
    pub fn new(centre: DVec3, radius: f64) -> Result<Self, SynthError> {
        let radius = positive("sphere", "radius", radius)?;
        require(
            centre.is_finite(),
            "sphere",
            "centre",
            f64::NAN,
            "must be finite",
        )?;
        Ok(SphereSampler { centre, radius })
    }
}

impl Sampler for SphereSampler {
    fn sample(&self, rng: &mut Rng) -> Sample {
        let n = rng.unit_vector();
        Sample {
            p: self.centre + n * self.radius,
            n,
        }
    }
    fn area(&self) -> f64 {
        4.0 * PI * self.radius * self.radius
    }
}

/// Ring torus around the z axis, centred at the origin:
/// `((R + r cos v) cos u, (R + r cos v) sin u, r sin v)`, outward normals.
/// Area element `r (R + r cos v)`: accept `v` with `(R + r cos v) / (R + r)`.
#[derive(Clone, Debug)]
pub struct TorusSampler {
    major: f64,
    minor: f64,
}

impl TorusSampler {
    pub fn new(major: f64, minor: f64) -> Result<Self, SynthError> {
        let major = positive("torus", "major", major)?;
        let minor = positive("torus", "minor", minor)?;
        require(
            minor < major,
            "torus",
            "minor",
            minor,
            "must be < major (ring torus)",
        )?;
        Ok(TorusSampler { major, minor })
    }
}

impl Sampler for TorusSampler {
    fn sample(&self, rng: &mut Rng) -> Sample {
        let (cv, sv) = loop {
            let (cv, sv) = rng.unit_circle();
            let accept = (self.major + self.minor * cv) / (self.major + self.minor);
            if rng.uniform() < accept {
                break (cv, sv);
            }
        };
        let (cu, su) = rng.unit_circle();
        let n = DVec3::new(cv * cu, cv * su, sv);
        let ring = DVec3::new(self.major * cu, self.major * su, 0.0);
        Sample {
            p: ring + n * self.minor,
            n,
        }
    }
    fn area(&self) -> f64 {
        4.0 * PI * PI * self.major * self.minor
    }
}

/// Moebius strip `x(u, t) = ((R + t c) cos u, (R + t c) sin u, t s)` with
/// `c = cos(u/2)`, `s = sin(u/2)`, `u in [0, 2 pi)`, `t in [-w/2, w/2]`.
///
/// `|x_u x x_t|^2 = (R + t c)^2 + t^2 / 4`. The normal is
/// `x_u x x_t` normalised: continuous in `(u, t)` on the parameter
/// rectangle, and it flips across the seam `u = 0 ~ 2 pi` (the strip is not
/// orientable).
#[derive(Clone, Debug)]
pub struct MoebiusSampler {
    radius: f64,
    half_width: f64,
}

impl MoebiusSampler {
    pub fn new(radius: f64, width: f64) -> Result<Self, SynthError> {
        let radius = positive("moebius", "radius", radius)?;
        let width = positive("moebius", "width", width)?;
        require(
            width < radius,
            "moebius",
            "width",
            width,
            "must be < radius",
        )?;
        Ok(MoebiusSampler {
            radius,
            half_width: width * 0.5,
        })
    }

    fn area_element(&self, c: f64, t: f64) -> f64 {
        let a = self.radius + t * c;
        (a * a + 0.25 * t * t).sqrt()
    }

    /// Point and unit normal at half-angle `(c, s) = (cos u/2, sin u/2)` and
    /// offset `t`.
    pub fn at(&self, c: f64, s: f64, t: f64) -> Sample {
        let (cu, su) = (c * c - s * s, 2.0 * c * s);
        let a = self.radius + t * c;
        let p = DVec3::new(a * cu, a * su, t * s);
        let xu = DVec3::new(
            -a * su - 0.5 * t * s * cu,
            a * cu - 0.5 * t * s * su,
            0.5 * t * c,
        );
        let xt = DVec3::new(c * cu, c * su, s);
        let n = xu.cross(xt);
        Sample {
            p,
            n: n / n.length(),
        }
    }
}

impl Sampler for MoebiusSampler {
    fn sample(&self, rng: &mut Rng) -> Sample {
        let bound = self.area_element(1.0, self.half_width);
        loop {
            // u/2 uniform in [0, pi): fold the circle's lower half up.
            let (mut c, mut s) = rng.unit_circle();
            if s < 0.0 {
                (c, s) = (-c, -s);
            }
            let t = rng.range(-self.half_width, self.half_width);
            if rng.uniform() * bound < self.area_element(c, t) {
                return self.at(c, s, t);
            }
        }
    }

    /// Midpoint rule on the parameter rectangle (the integrand is smooth and
    /// periodic in u, so this converges fast).
    fn area(&self) -> f64 {
        const NU: usize = 512;
        const NT: usize = 64;
        let (du, dt) = (2.0 * PI / NU as f64, 2.0 * self.half_width / NT as f64);
        let mut sum = 0.0;
        for i in 0..NU {
            let c = ((i as f64 + 0.5) * du * 0.5).cos();
            for j in 0..NT {
                let t = -self.half_width + (j as f64 + 0.5) * dt;
                sum += self.area_element(c, t);
            }
        }
        sum * du * dt
    }
}
