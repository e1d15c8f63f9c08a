//! Parametric surfaces sampled uniformly by area: sphere, torus, the
//! (non-orientable) Moebius strip, an open tube (cylinder without caps) and
//! a capsule (a cylinder closed by hemispheres).
//!
//! Uniform-by-area sampling of a parametrised surface: draw parameters
//! uniformly and accept with probability `|x_u x x_v| / max |x_u x x_v|`
//! (rejection sampling, e.g. Williamson 1987, "Random selection of points
//! distributed on curved surfaces"). Angles come from [`Rng::unit_circle`],
//! so no trigonometric function (and no platform `libm`) is involved.

use super::error::{positive, require, SynthError};
use super::{Sample, Sampler};
use crate::rng::Rng;
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

/// Open tube around the z axis: `x^2 + y^2 = radius^2`, `|z| <= length/2`,
/// no caps; outward (radial) normals. The area element is constant in
/// `(angle, z)`, so both are drawn uniformly.
#[derive(Clone, Debug)]
pub struct CylinderSampler {
    radius: f64,
    half_length: f64,
}

impl CylinderSampler {
    pub fn new(radius: f64, length: f64) -> Result<Self, SynthError> {
        let radius = positive("cylinder", "radius", radius)?;
        let length = positive("cylinder", "length", length)?;
        Ok(CylinderSampler {
            radius,
            half_length: length * 0.5,
        })
    }
}

impl Sampler for CylinderSampler {
    fn sample(&self, rng: &mut Rng) -> Sample {
        let (c, s) = rng.unit_circle();
        let z = rng.range(-self.half_length, self.half_length);
        let n = DVec3::new(c, s, 0.0);
        Sample {
            p: n * self.radius + DVec3::Z * z,
            n,
        }
    }
    fn area(&self) -> f64 {
        4.0 * PI * self.radius * self.half_length
    }
}

/// Capsule around the z axis: the tube `x^2 + y^2 = radius^2`,
/// `|z| <= length/2`, closed by hemispheres of the same radius centred at
/// `z = +-length/2`; outward normals. A sample picks the tube or the caps in
/// proportion to their areas, then a point uniform on that part (the two
/// caps together are a sphere split at its equator).
#[derive(Clone, Debug)]
pub struct CapsuleSampler {
    tube: CylinderSampler,
}

impl CapsuleSampler {
    pub fn new(radius: f64, length: f64) -> Result<Self, SynthError> {
        let radius = positive("capsule", "radius", radius)?;
        let length = positive("capsule", "length", length)?;
        Ok(CapsuleSampler {
            tube: CylinderSampler {
                radius,
                half_length: length * 0.5,
            },
        })
    }

    /// Area of the two hemispheres together.
    fn caps_area(&self) -> f64 {
        4.0 * PI * self.tube.radius * self.tube.radius
    }
}

impl Sampler for CapsuleSampler {
    fn sample(&self, rng: &mut Rng) -> Sample {
        if rng.uniform() * self.area() < self.tube.area() {
            return self.tube.sample(rng);
        }
        let n = rng.unit_vector();
        // The upper hemisphere of the direction sphere goes to the top cap.
        let centre = DVec3::Z * self.tube.half_length.copysign(n.z);
        Sample {
            p: centre + n * self.tube.radius,
            n,
        }
    }
    fn area(&self) -> f64 {
        self.tube.area() + self.caps_area()
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Distance of `p` to the capsule's surface (radius `r`, straight part
    /// `|z| <= h`): its distance to the axis segment, minus `r`.
    fn capsule_distance(p: DVec3, r: f64, h: f64) -> f64 {
        let axis = DVec3::Z * p.z.clamp(-h, h);
        ((p - axis).length() - r).abs()
    }

    #[test]
    fn cylinder_samples_lie_on_the_tube_with_radial_normals_uniformly() {
        let (r, len, seed) = (0.3, 2.0, 1);
        let s = CylinderSampler::new(r, len).unwrap();
        assert!((s.area() - 2.0 * PI * r * len).abs() < 1e-12);
        let mut rng = Rng::new(seed);
        let mut bins = [0usize; 4];
        let n = 20_000;
        for i in 0..n {
            let q = s.sample(&mut rng);
            let rho = q.p.truncate().length();
            assert!((rho - r).abs() < 1e-9, "seed {seed} point {i}: rho {rho}");
            assert!(q.p.z.abs() <= 0.5 * len, "seed {seed} point {i}");
            assert!((q.n.length() - 1.0).abs() < 1e-12, "seed {seed} point {i}");
            assert!(q.n.z == 0.0 && q.n.dot(q.p) > 0.0, "seed {seed} point {i}");
            bins[((q.p.z / len + 0.5) * 4.0).clamp(0.0, 3.0) as usize] += 1;
        }
        // z uniform: each quarter holds n/4, sd sqrt(n 3/16) = 61.
        for b in bins {
            assert!((b as f64 - 5000.0).abs() < 300.0, "seed {seed}: {bins:?}");
        }
    }

    #[test]
    fn capsule_samples_lie_on_it_and_the_caps_get_their_area_share() {
        let (r, len, seed) = (0.3, 1.0, 2);
        let s = CapsuleSampler::new(r, len).unwrap();
        let caps = 4.0 * PI * r * r;
        let total = caps + 2.0 * PI * r * len;
        assert!((s.area() - total).abs() < 1e-12);
        let mut rng = Rng::new(seed);
        let (n, h) = (20_000, 0.5 * len);
        let (mut on_caps, mut top) = (0usize, 0usize);
        for i in 0..n {
            let q = s.sample(&mut rng);
            let d = capsule_distance(q.p, r, h);
            assert!(d < 1e-9, "seed {seed} point {i}: off by {d}");
            assert!((q.n.length() - 1.0).abs() < 1e-12, "seed {seed} point {i}");
            // Outward: the normal is the direction from the axis segment.
            let axis = DVec3::Z * q.p.z.clamp(-h, h);
            let want = (q.p - axis) / r;
            assert!((q.n - want).length() < 1e-9, "seed {seed} point {i}");
            if q.p.z.abs() > h {
                on_caps += 1;
                top += usize::from(q.p.z > 0.0);
            }
        }
        // Cap share 0.375, sd sqrt(0.375 0.625 / n) = 0.0034.
        let share = on_caps as f64 / n as f64;
        assert!(
            (share - caps / total).abs() < 0.015,
            "seed {seed}: cap share {share} vs {}",
            caps / total
        );
        let top_share = top as f64 / on_caps as f64;
        assert!(
            (top_share - 0.5).abs() < 0.03,
            "seed {seed}: top {top_share}"
        );
    }

    #[test]
    fn tube_and_capsule_reject_bad_sizes() {
        assert!(CylinderSampler::new(0.0, 1.0).is_err());
        assert!(CylinderSampler::new(1.0, f64::NAN).is_err());
        assert!(CapsuleSampler::new(-1.0, 1.0).is_err());
        assert!(CapsuleSampler::new(1.0, f64::INFINITY).is_err());
    }
}
