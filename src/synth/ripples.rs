//! Concentric ripples on a disc, for valley-ridge extraction (paper 5):
//! `z = amplitude sin(2 pi rho / wavelength)`, `rho = sqrt(x^2 + y^2)`, with
//! circular crests (ridges) and troughs (valleys) as known feature lines.
//!
//! The crests are exact ridge lines: at `z'(rho) = 0` the profile's
//! curvature is extremal along the radius because `z''' = 0` there too, and
//! the circumferential curvature (`z' / rho` over the area element) is 0.
//! The centre is a cone point (`z'(0) = amplitude 2 pi / wavelength`), not a
//! feature line.

use super::creased::TrueSegment;
use super::error::{positive, SynthError};
use super::{Sample, Sampler};
use crate::geom::LineKind;
use crate::rng::Rng;
use glam::DVec3;
use std::f64::consts::{PI, TAU};

/// Largest chord error (sagitta) of a true circle's segments, relative to
/// the disc's radius.
const CHORD_ERROR: f64 = 1e-5;

/// Sampler of the ripples: uniform on the disc in `(x, y)`, kept with
/// probability proportional to the area element `sqrt(1 + z'(rho)^2)`, so
/// uniform over the surface. Normals up.
#[derive(Clone, Debug)]
pub struct RipplesSampler {
    radius: f64,
    amplitude: f64,
    wavelength: f64,
    max_element: f64,
    area: f64,
}

impl RipplesSampler {
    pub fn new(radius: f64, amplitude: f64, wavelength: f64) -> Result<Self, SynthError> {
        let radius = positive("ripples", "radius", radius)?;
        let amplitude = positive("ripples", "amplitude", amplitude)?;
        let wavelength = positive("ripples", "wavelength", wavelength)?;
        let mut s = RipplesSampler {
            radius,
            amplitude,
            wavelength,
            max_element: (1.0 + (amplitude * TAU / wavelength).powi(2)).sqrt(),
            area: 0.0,
        };
        s.area = s.integrated_area();
        Ok(s)
    }

    fn omega(&self) -> f64 {
        TAU / self.wavelength
    }

    /// `z'(rho)`.
    fn slope(&self, rho: f64) -> f64 {
        self.amplitude * self.omega() * (self.omega() * rho).cos()
    }

    /// `2 pi integral rho sqrt(1 + z'^2) d rho` by the midpoint rule.
    fn integrated_area(&self) -> f64 {
        let steps = 20_000;
        let dr = self.radius / steps as f64;
        let sum: f64 = (0..steps)
            .map(|i| {
                let rho = (i as f64 + 0.5) * dr;
                rho * (1.0 + self.slope(rho).powi(2)).sqrt()
            })
            .sum();
        TAU * sum * dr
    }

    /// Crest circles `rho = (k + 1/4) wavelength` at `z = amplitude`
    /// (ridges) and trough circles `rho = (k + 3/4) wavelength` at
    /// `z = -amplitude` (valleys) inside the disc, each a closed chain of
    /// segments whose chord error is under `1e-5 radius`.
    pub fn truth(&self) -> Vec<TrueSegment> {
        let mut lines = Vec::new();
        let last = (self.radius / self.wavelength).ceil() as u64;
        for k in 0..=last {
            for (quarter, kind, z) in [
                (0.25, LineKind::Ridge, self.amplitude),
                (0.75, LineKind::Valley, -self.amplitude),
            ] {
                let rho = (k as f64 + quarter) * self.wavelength;
                if rho > 0.0 && rho < self.radius {
                    push_circle(&mut lines, kind, rho, z, CHORD_ERROR * self.radius);
                }
            }
        }
        lines
    }
}

/// The circle of radius `rho` around the z axis at height `z`, as a closed
/// chain of equal chords with sagitta at most `chord_error`.
fn push_circle(lines: &mut Vec<TrueSegment>, kind: LineKind, rho: f64, z: f64, chord_error: f64) {
    // Sagitta rho (1 - cos(pi / m)) <= rho pi^2 / (2 m^2).
    let m = ((PI * (rho / (2.0 * chord_error)).sqrt()).ceil() as usize).max(8);
    let at = |i: usize| {
        let t = TAU * (i % m) as f64 / m as f64;
        DVec3::new(rho * t.cos(), rho * t.sin(), z)
    };
    lines.extend((0..m).map(|i| TrueSegment {
        kind,
        a: at(i),
        b: at(i + 1),
    }));
}

impl Sampler for RipplesSampler {
    fn sample(&self, rng: &mut Rng) -> Sample {
        let r = self.radius;
        loop {
            let x = rng.range(-r, r);
            let y = rng.range(-r, r);
            let rho = (x * x + y * y).sqrt();
            if rho > r {
                continue;
            }
            let dz = self.slope(rho);
            let element = (1.0 + dz * dz).sqrt();
            if rng.uniform() * self.max_element <= element {
                // At the cone point (probability 0) any upward normal will do.
                let n = if rho > 0.0 {
                    DVec3::new(-dz * x / rho, -dz * y / rho, 1.0) / element
                } else {
                    DVec3::Z
                };
                return Sample {
                    p: DVec3::new(x, y, self.amplitude * (self.omega() * rho).sin()),
                    n,
                };
            }
        }
    }
    fn area(&self) -> f64 {
        self.area
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::FRAC_1_SQRT_2;

    fn preset() -> RipplesSampler {
        RipplesSampler::new(2.0, 0.0875, 0.35).unwrap()
    }

    #[test]
    fn samples_lie_on_the_ripples_with_upward_gradient_normals() {
        let (s, seed) = (preset(), 3);
        let mut rng = Rng::new(seed);
        for i in 0..20_000 {
            let q = s.sample(&mut rng);
            let rho = q.p.truncate().length();
            assert!(rho <= 2.0, "seed {seed} point {i}: rho {rho}");
            let z = 0.0875 * (TAU * rho / 0.35).sin();
            assert!((q.p.z - z).abs() < 1e-9, "seed {seed} point {i}");
            assert!((q.n.length() - 1.0).abs() < 1e-12, "seed {seed} point {i}");
            assert!(q.n.z > 0.0, "seed {seed} point {i}: {}", q.n);
            // Normal against the gradient by central differences.
            let (e, f) = (1e-6, |x: f64, y: f64| {
                0.0875 * (TAU * (x * x + y * y).sqrt() / 0.35).sin()
            });
            let gx = (f(q.p.x + e, q.p.y) - f(q.p.x - e, q.p.y)) / (2.0 * e);
            let gy = (f(q.p.x, q.p.y + e) - f(q.p.x, q.p.y - e)) / (2.0 * e);
            let want = DVec3::new(-gx, -gy, 1.0).normalize();
            assert!((q.n - want).length() < 1e-6, "seed {seed} point {i}");
        }
    }

    #[test]
    fn samples_are_uniform_by_area() {
        // Share of the points on the steep half of each wavelength (where
        // |cos| > cos 45 degrees) against its share of the area.
        let (s, seed, n) = (preset(), 4, 40_000);
        let steep = |rho: f64| (TAU * rho / 0.35).cos().abs() > FRAC_1_SQRT_2;
        let mut rng = Rng::new(seed);
        let got = (0..n).filter(|_| steep(s.sample(&mut rng).p.truncate().length()));
        let got = got.count() as f64 / n as f64;
        let steps = 200_000;
        let dr = 2.0 / steps as f64;
        let steep_area: f64 = (0..steps)
            .map(|i| (i as f64 + 0.5) * dr)
            .filter(|&rho| steep(rho))
            .map(|rho| TAU * rho * (1.0 + s.slope(rho).powi(2)).sqrt() * dr)
            .sum();
        let want = steep_area / s.area();
        // sd sqrt(0.25 / n) = 0.0025.
        assert!((got - want).abs() < 0.0125, "seed {seed}: {got} vs {want}");
        // The area against the flat disc's: larger, below the steepest bound.
        let flat = PI * 4.0;
        assert!(s.area() > 1.2 * flat && s.area() < s.max_element * flat);
    }

    #[test]
    fn truth_circles_are_closed_chains_on_the_crests() {
        let s = preset();
        let t = s.truth();
        let mut circles: Vec<(LineKind, f64, usize)> = Vec::new();
        for (i, seg) in t.iter().enumerate() {
            for p in [seg.a, seg.b] {
                let rho = p.truncate().length();
                let want = if seg.kind == LineKind::Ridge {
                    0.0875
                } else {
                    -0.0875
                };
                assert_eq!(p.z, want, "segment {i}");
                assert!((0.0875 * (TAU * rho / 0.35).sin() - p.z).abs() < 1e-9);
                assert!(
                    s.slope(rho).abs() < 1e-9,
                    "segment {i}: z' {}",
                    s.slope(rho)
                );
            }
            // Chord error: the chord's midpoint against the circle.
            let rho = seg.a.truncate().length();
            let sagitta = rho - (0.5 * (seg.a + seg.b)).truncate().length();
            assert!(sagitta > 0.0 && sagitta < 2e-5, "segment {i}: {sagitta}");
            match circles.last_mut() {
                Some(c) if c.0 == seg.kind && (c.1 - rho).abs() < 1e-12 => {
                    assert_eq!(t[i - 1].b, seg.a, "segment {i}: chain broken");
                    c.2 += 1;
                }
                _ => circles.push((seg.kind, rho, 1)),
            }
        }
        // Crests 0.0875 + 0.35 k up to 1.8375, troughs 0.2625 up to 1.6625.
        assert_eq!(circles.len(), 11, "{circles:?}");
        let mut start = 0;
        for (k, (kind, rho, m)) in circles.iter().enumerate() {
            let quarter = if k % 2 == 0 { 0.25 } else { 0.75 };
            let ridge = k % 2 == 0;
            assert_eq!(*kind == LineKind::Ridge, ridge, "circle {k}");
            assert!((rho - (k / 2) as f64 * 0.35 - quarter * 0.35).abs() < 1e-12);
            assert_eq!(t[start + m - 1].b, t[start].a, "circle {k} not closed");
            start += m;
        }
    }

    #[test]
    fn bad_parameters_are_errors() {
        assert!(RipplesSampler::new(0.0, 0.1, 0.3).is_err());
        assert!(RipplesSampler::new(1.0, -0.1, 0.3).is_err());
        assert!(RipplesSampler::new(1.0, 0.1, f64::NAN).is_err());
    }
}
