//! Surfaces with known feature lines, for valley-ridge extraction (paper 5):
//! a step profile extruded into a closed prism (a stepped block, a box with
//! a notch: every convex edge a ridge, every concave edge a valley), and a
//! sheet with sinusoidal crests (ridges) and troughs (valleys).
//!
//! Ridge means convex seen from outside (the normals' side), valley concave,
//! as in the paper's text.

use super::error::{positive, require, SynthError};
use super::{Sample, Sampler};
use crate::geom::LineKind;
use crate::rng::Rng;
use glam::DVec3;
use std::f64::consts::{FRAC_PI_2, TAU};

/// A straight piece of a true feature line.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrueSegment {
    /// Ridge (convex) or valley (concave).
    pub kind: LineKind,
    /// One end of the segment.
    pub a: DVec3,
    /// The other end of the segment.
    pub b: DVec3,
}

/// Columns `[xs[i], xs[i+1]] x [0, heights[i]]` in the xz-plane, extruded
/// along y over `[0, width]`: a closed prism.
#[derive(Clone, Debug, PartialEq)]
pub struct StepProfile {
    /// Column edges along x, increasing; one more than `heights`.
    pub xs: Vec<f64>,
    /// Height of each column (z of its top).
    pub heights: Vec<f64>,
    /// Extent of the prism along y.
    pub width: f64,
}

impl StepProfile {
    /// Three steps down: 3 x 3 x 3 overall, two concave edges.
    pub fn stepped_block() -> Self {
        StepProfile {
            xs: vec![0.0, 1.0, 2.0, 3.0],
            heights: vec![3.0, 2.0, 1.0],
            width: 3.0,
        }
    }

    /// A 5 x 3 x 2 box with a 1 x 1 groove across its top.
    pub fn notched_box() -> Self {
        StepProfile {
            xs: vec![0.0, 2.0, 3.0, 5.0],
            heights: vec![2.0, 1.0, 2.0],
            width: 3.0,
        }
    }

    fn validate(&self) -> Result<(), SynthError> {
        let name = "step-profile";
        positive(name, "width", self.width)?;
        require(
            self.xs.len() == self.heights.len() + 1 && !self.heights.is_empty(),
            name,
            "columns",
            self.heights.len() as f64,
            "needs one more x than heights, and at least one column",
        )?;
        for h in &self.heights {
            positive(name, "height", *h)?;
        }
        for w in self.xs.windows(2) {
            require(w[1] > w[0], name, "x", w[1], "xs must increase")?;
        }
        Ok(())
    }

    /// The profile's outline as (x, z) vertices, counter-clockwise: bottom
    /// left, bottom right, then up and along the top back to the left.
    fn outline(&self) -> Vec<(f64, f64)> {
        let n = self.heights.len();
        let mut v = vec![(self.xs[0], 0.0), (self.xs[n], 0.0)];
        for i in (0..n).rev() {
            v.push((self.xs[i + 1], self.heights[i]));
            v.push((self.xs[i], self.heights[i]));
        }
        // Equal neighbouring heights make collinear vertices: drop them.
        let mut out: Vec<(f64, f64)> = Vec::new();
        for p in v {
            if out.last() != Some(&p) {
                out.push(p);
            }
        }
        let m = out.len();
        (0..m)
            .filter(|&i| {
                let (a, b, c) = (out[(i + m - 1) % m], out[i], out[(i + 1) % m]);
                (b.0 - a.0) * (c.1 - b.1) - (b.1 - a.1) * (c.0 - b.0) != 0.0
            })
            .map(|i| out[i])
            .collect()
    }

    /// Every convex edge (ridge) and concave edge (valley) of the prism.
    pub fn truth(&self) -> Vec<TrueSegment> {
        let o = self.outline();
        let m = o.len();
        let at = |p: (f64, f64), y: f64| DVec3::new(p.0, y, p.1);
        let mut lines = Vec::new();
        for i in 0..m {
            let (a, b, c) = (o[(i + m - 1) % m], o[i], o[(i + 1) % m]);
            // The outline runs counter-clockwise: a left turn is convex.
            let turn = (b.0 - a.0) * (c.1 - b.1) - (b.1 - a.1) * (c.0 - b.0);
            let kind = if turn > 0.0 {
                LineKind::Ridge
            } else {
                LineKind::Valley
            };
            lines.push(TrueSegment {
                kind,
                a: at(b, 0.0),
                b: at(b, self.width),
            });
            // Caps meet the sides at right angles: convex.
            for y in [0.0, self.width] {
                lines.push(TrueSegment {
                    kind: LineKind::Ridge,
                    a: at(b, y),
                    b: at(c, y),
                });
            }
        }
        lines
    }
}

/// A planar rectangle `origin + s e1 + t e2`, `s, t` in `[0, 1]`.
#[derive(Clone, Copy, Debug)]
struct Rect {
    origin: DVec3,
    e1: DVec3,
    e2: DVec3,
    normal: DVec3,
}

/// Area-uniform sampler over a [`StepProfile`] prism's faces.
#[derive(Clone, Debug)]
pub struct StepSampler {
    rects: Vec<Rect>,
    cumulative: Vec<f64>,
}

impl StepSampler {
    pub fn new(p: &StepProfile) -> Result<Self, SynthError> {
        p.validate()?;
        let w = p.width;
        let n = p.heights.len();
        let mut rects = Vec::new();
        let y = DVec3::Y * w;
        for i in 0..n {
            let (x0, x1, h) = (p.xs[i], p.xs[i + 1], p.heights[i]);
            let dx = DVec3::X * (x1 - x0);
            // Caps (y = 0 and y = w), bottom and top of the column.
            rects.push(rect(DVec3::new(x0, 0.0, 0.0), dx, DVec3::Z * h, -DVec3::Y));
            rects.push(rect(DVec3::new(x0, w, 0.0), dx, DVec3::Z * h, DVec3::Y));
            rects.push(rect(DVec3::new(x0, 0.0, 0.0), dx, y, -DVec3::Z));
            rects.push(rect(DVec3::new(x0, 0.0, h), dx, y, DVec3::Z));
        }
        // Left and right walls, and the risers between columns.
        rects.push(rect(
            DVec3::new(p.xs[0], 0.0, 0.0),
            DVec3::Z * p.heights[0],
            y,
            -DVec3::X,
        ));
        rects.push(rect(
            DVec3::new(p.xs[n], 0.0, 0.0),
            DVec3::Z * p.heights[n - 1],
            y,
            DVec3::X,
        ));
        for i in 0..n - 1 {
            let (a, b) = (p.heights[i], p.heights[i + 1]);
            if a != b {
                let normal = if a > b { DVec3::X } else { -DVec3::X };
                let base = DVec3::new(p.xs[i + 1], 0.0, a.min(b));
                rects.push(rect(base, DVec3::Z * (a - b).abs(), y, normal));
            }
        }
        let mut total = 0.0;
        let cumulative = rects
            .iter()
            .map(|r| {
                total += r.e1.cross(r.e2).length();
                total
            })
            .collect();
        Ok(StepSampler { rects, cumulative })
    }
}

fn rect(origin: DVec3, e1: DVec3, e2: DVec3, normal: DVec3) -> Rect {
    Rect {
        origin,
        e1,
        e2,
        normal,
    }
}

impl Sampler for StepSampler {
    fn sample(&self, rng: &mut Rng) -> Sample {
        let u = rng.uniform() * self.area();
        let k = self.cumulative.partition_point(|&c| c <= u);
        let r = self.rects[k.min(self.rects.len() - 1)];
        let (s, t) = (rng.uniform(), rng.uniform());
        Sample {
            p: r.origin + r.e1 * s + r.e2 * t,
            n: r.normal,
        }
    }
    fn area(&self) -> f64 {
        self.cumulative.last().copied().unwrap_or(0.0)
    }
}

/// `z = amplitude sin(2 pi x / wavelength)` over `[-side/2, side/2]^2`,
/// normals up: crests are ridges, troughs valleys.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WavySheet {
    /// Side of the square.
    pub side: f64,
    /// Height of the crests above z = 0.
    pub amplitude: f64,
    /// Distance between crests along x.
    pub wavelength: f64,
}

impl WavySheet {
    fn omega(&self) -> f64 {
        TAU / self.wavelength
    }

    /// Crest (ridge) and trough (valley) lines across the sheet.
    pub fn truth(&self) -> Vec<TrueSegment> {
        let h = self.side / 2.0;
        let mut lines = Vec::new();
        let first = ((-h / self.wavelength).floor() - 1.0) as i64;
        let last = ((h / self.wavelength).ceil() + 1.0) as i64;
        for k in first..=last {
            for (phase, kind, z) in [
                (FRAC_PI_2, LineKind::Ridge, self.amplitude),
                (-FRAC_PI_2, LineKind::Valley, -self.amplitude),
            ] {
                let x = (phase + TAU * k as f64) / self.omega();
                if x > -h && x < h {
                    lines.push(TrueSegment {
                        kind,
                        a: DVec3::new(x, -h, z),
                        b: DVec3::new(x, h, z),
                    });
                }
            }
        }
        lines
    }
}

/// Sampler of a [`WavySheet`]: uniform in `(x, y)`, kept with probability
/// proportional to the area element, so uniform over the surface.
#[derive(Clone, Debug)]
pub struct WavySampler {
    sheet: WavySheet,
    max_element: f64,
    area: f64,
}

impl WavySampler {
    pub fn new(sheet: WavySheet) -> Result<Self, SynthError> {
        positive("wavy-sheet", "side", sheet.side)?;
        positive("wavy-sheet", "amplitude", sheet.amplitude)?;
        positive("wavy-sheet", "wavelength", sheet.wavelength)?;
        let slope = sheet.amplitude * sheet.omega();
        // Area: the element integrated over x by the midpoint rule, times side.
        let steps = 20_000;
        let dx = sheet.side / steps as f64;
        let element = |x: f64| (1.0 + (slope * (sheet.omega() * x).cos()).powi(2)).sqrt();
        let area = (0..steps)
            .map(|i| element(-sheet.side / 2.0 + (i as f64 + 0.5) * dx) * dx)
            .sum::<f64>()
            * sheet.side;
        Ok(WavySampler {
            sheet,
            max_element: (1.0 + slope * slope).sqrt(),
            area,
        })
    }
}

impl Sampler for WavySampler {
    fn sample(&self, rng: &mut Rng) -> Sample {
        let s = &self.sheet;
        let h = s.side / 2.0;
        loop {
            let x = rng.range(-h, h);
            let y = rng.range(-h, h);
            let dz = s.amplitude * s.omega() * (s.omega() * x).cos();
            let element = (1.0 + dz * dz).sqrt();
            if rng.uniform() * self.max_element <= element {
                return Sample {
                    p: DVec3::new(x, y, s.amplitude * (s.omega() * x).sin()),
                    n: DVec3::new(-dz, 0.0, 1.0) / element,
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

    #[test]
    fn stepped_block_has_two_valleys_and_closed_faces() {
        let p = StepProfile::stepped_block();
        let t = p.truth();
        let valleys: Vec<_> = t.iter().filter(|s| s.kind == LineKind::Valley).collect();
        assert_eq!(valleys.len(), 2);
        for v in &valleys {
            // The inner corners (1, 2) and (2, 1) in (x, z).
            assert!(
                v.a.x + v.a.z == 3.0 && v.a.x != 0.0 && v.a.z != 0.0,
                "{v:?}"
            );
        }
        // 8 outline vertices: 8 lines along y and 16 cap edges.
        assert_eq!(t.len(), 24);
        let s = StepSampler::new(&p).unwrap();
        // Caps 2 x 6, bottom 9, tops 9, walls 9 + 3, risers 6.
        assert!((s.area() - 48.0).abs() < 1e-12, "{}", s.area());
    }

    #[test]
    fn notch_bottom_edges_are_valleys_rims_ridges() {
        let t = StepProfile::notched_box().truth();
        let along_y = |k: LineKind| {
            let mut v: Vec<(f64, f64)> = t
                .iter()
                .filter(|s| s.kind == k && s.a.y != s.b.y)
                .map(|s| (s.a.x, s.a.z))
                .collect();
            v.sort_by(|a, b| a.partial_cmp(b).unwrap());
            v
        };
        assert_eq!(along_y(LineKind::Valley), vec![(2.0, 1.0), (3.0, 1.0)]);
        assert_eq!(
            along_y(LineKind::Ridge),
            vec![
                (0.0, 0.0),
                (0.0, 2.0),
                (2.0, 2.0),
                (3.0, 2.0),
                (5.0, 0.0),
                (5.0, 2.0)
            ]
        );
    }

    #[test]
    fn wavy_sheet_samples_lie_on_it_with_crests_as_ridges() {
        let sheet = WavySheet {
            side: 2.0,
            amplitude: 0.1,
            wavelength: 0.5,
        };
        let s = WavySampler::new(sheet).unwrap();
        let mut rng = Rng::new(1);
        for _ in 0..100 {
            let p = s.sample(&mut rng).p;
            assert!((p.z - 0.1 * (TAU * p.x / 0.5).sin()).abs() < 1e-12);
        }
        let t = sheet.truth();
        assert_eq!(t.iter().filter(|l| l.kind == LineKind::Ridge).count(), 4);
        assert_eq!(t.iter().filter(|l| l.kind == LineKind::Valley).count(), 4);
        assert!(t
            .iter()
            .all(|l| (l.a.z > 0.0) == (l.kind == LineKind::Ridge)));
    }
}
