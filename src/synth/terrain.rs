//! Terrain with box buildings: a smooth height field over a square, sampled
//! with a density that rises smoothly (linearly) along x, plus axis-aligned
//! box buildings whose roofs and walls are sampled (no floors, no ground
//! under a footprint). A stand-in for an airborne/terrestrial city scan.
//!
//! Sampling is exact rejection from density `w(x) dA` (e.g. Devroye 1986,
//! "Non-Uniform Random Variate Generation", II.3): propose uniformly on a
//! bounding measure (ground: square x max slope factor; roofs: footprints;
//! walls: perimeter x [lowest ground, roof]), accept with
//! `(true area element / bound) * w(x) / w_max`, and reject ground inside a
//! footprint and wall below the ground.
//!
//! The height field is a sum of compact polynomial hills `(1 - q^2)^3`
//! (C^2-smooth), chosen over sines so that sampling needs no platform `libm`.

use super::error::{finite, positive, SynthError};
use super::{Sample, Sampler};
use crate::rng::Rng;
use glam::{DVec2, DVec3};

/// An axis-aligned box building: footprint `[min, max]` in x, y; walls rise
/// from the ground to the flat roof at absolute height `roof`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Building {
    /// Footprint corner of smallest x and y.
    pub min: DVec2,
    /// Footprint corner of largest x and y.
    pub max: DVec2,
    /// Absolute height of the flat roof.
    pub roof: f64,
}

/// Parameters of the terrain scene; the square is `[-side/2, side/2]^2`.
#[derive(Clone, Debug, PartialEq)]
pub struct Terrain {
    /// Side of the square.
    pub side: f64,
    /// Vertical scale of the hills: ground height lies in
    /// `[-0.3 relief, 1.05 relief]`.
    pub relief: f64,
    /// Density per unit area at `x = +side/2` over that at `x = -side/2`;
    /// linear in between.
    pub density_ratio: f64,
    /// The buildings standing on the ground.
    pub buildings: Vec<Building>,
}

/// Hills as (centre, radius) in units of `side/2`, amplitude in units of relief.
const HILLS: [([f64; 2], f64, f64); 4] = [
    ([-0.5, -0.3], 0.8, 0.5),
    ([0.4, 0.5], 0.7, 0.35),
    ([0.3, -0.6], 0.5, -0.3),
    ([-0.6, 0.6], 0.6, 0.2),
];

/// `max_q 6 q (1 - q^2)^2` (at `q = 1/sqrt(5)`): bound of `|grad hill| * radius`.
const HILL_SLOPE_BOUND: f64 = 1.717_382_5;

impl Terrain {
    /// A 100 x 100 scene with 3 m of relief, density 10:1 across x and
    /// three buildings of different heights.
    pub fn city() -> Self {
        let b = |x0: f64, y0: f64, x1: f64, y1: f64, roof: f64| Building {
            min: DVec2::new(x0, y0),
            max: DVec2::new(x1, y1),
            roof,
        };
        Terrain {
            side: 100.0,
            relief: 3.0,
            density_ratio: 10.0,
            buildings: vec![
                b(-30.0, -20.0, -15.0, -5.0, 12.0),
                b(5.0, 10.0, 25.0, 22.0, 20.0),
                b(20.0, -35.0, 32.0, -25.0, 8.0),
            ],
        }
    }

    /// Ground height `h(x, y)` and its gradient.
    pub fn height(&self, x: f64, y: f64) -> (f64, DVec2) {
        let half = self.side * 0.5;
        let mut h = 0.0;
        let mut grad = DVec2::ZERO;
        for &([cx, cy], radius, amp) in &HILLS {
            let d = DVec2::new(x - cx * half, y - cy * half);
            let rho = radius * half;
            let q2 = d.length_squared() / (rho * rho);
            if q2 < 1.0 {
                let a = amp * self.relief;
                let w = 1.0 - q2;
                h += a * w * w * w;
                grad += d * (-6.0 * a * w * w / (rho * rho));
            }
        }
        (h, grad)
    }

    /// Relative sampling density at `x` (1 at the left edge, `density_ratio`
    /// at the right edge).
    pub fn density_weight(&self, x: f64) -> f64 {
        let t = (x / self.side + 0.5).clamp(0.0, 1.0);
        1.0 + (self.density_ratio - 1.0) * t
    }

    /// Lowest possible ground height.
    fn ground_low(&self) -> f64 {
        self.relief * HILLS.iter().map(|h| h.2.min(0.0)).sum::<f64>()
    }

    /// Highest possible ground height.
    fn ground_high(&self) -> f64 {
        self.relief * HILLS.iter().map(|h| h.2.max(0.0)).sum::<f64>()
    }

    fn slope_bound(&self) -> f64 {
        let half = self.side * 0.5;
        HILLS
            .iter()
            .map(|h| h.2.abs() * self.relief * HILL_SLOPE_BOUND / (h.1 * half))
            .sum()
    }

    /// Whether `(x, y)` is strictly inside some building's footprint.
    pub fn in_footprint(&self, x: f64, y: f64) -> bool {
        self.buildings
            .iter()
            .any(|b| x > b.min.x && x < b.max.x && y > b.min.y && y < b.max.y)
    }

    fn validate(&self) -> Result<(), SynthError> {
        positive("terrain", "side", self.side)?;
        finite("terrain", "relief", self.relief)?;
        if self.relief < 0.0 {
            return Err(SynthError::BadParameter {
                shape: "terrain",
                name: "relief",
                value: self.relief,
                requirement: "must be >= 0",
            });
        }
        if !(self.density_ratio.is_finite() && self.density_ratio >= 1.0) {
            return Err(SynthError::BadParameter {
                shape: "terrain",
                name: "density_ratio",
                value: self.density_ratio,
                requirement: "must be finite and >= 1",
            });
        }
        for (index, b) in self.buildings.iter().enumerate() {
            self.validate_building(index, b)?;
        }
        Ok(())
    }

    fn validate_building(&self, index: usize, b: &Building) -> Result<(), SynthError> {
        let half = self.side * 0.5;
        let bad = |reason| Err(SynthError::BadBuilding { index, reason });
        if !(b.min.is_finite() && b.max.is_finite() && b.roof.is_finite()) {
            return bad("has a non-finite coordinate");
        }
        if !(b.min.x < b.max.x && b.min.y < b.max.y) {
            return bad("has an empty footprint (need min < max)");
        }
        if b.min.x <= -half || b.min.y <= -half || b.max.x >= half || b.max.y >= half {
            return bad("footprint is not strictly inside the square");
        }
        if b.roof <= self.ground_high() {
            return bad("roof is not above the highest possible ground");
        }
        let overlaps = |o: &Building| {
            b.min.x <= o.max.x && o.min.x <= b.max.x && b.min.y <= o.max.y && o.min.y <= b.max.y
        };
        if self.buildings[..index].iter().any(overlaps) {
            return bad("footprint touches or overlaps an earlier building");
        }
        Ok(())
    }
}

/// What a proposal lands on.
#[derive(Clone, Copy, Debug)]
enum Part {
    Ground,
    Roof(usize),
    Wall(usize),
}

/// Sampler over [`Terrain`]; proposal weights are cumulative bounding measures.
#[derive(Clone, Debug)]
pub struct TerrainSampler<'a> {
    terrain: &'a Terrain,
    parts: Vec<(Part, f64)>,
    total: f64,
    slope_factor_bound: f64,
    low: f64,
    w_max: f64,
}

impl<'a> TerrainSampler<'a> {
    pub fn new(terrain: &'a Terrain) -> Result<Self, SynthError> {
        terrain.validate()?;
        let slope = terrain.slope_bound();
        let slope_factor_bound = (1.0 + slope * slope).sqrt();
        let low = terrain.ground_low();
        let mut parts = Vec::with_capacity(1 + 2 * terrain.buildings.len());
        let mut total = terrain.side * terrain.side * slope_factor_bound;
        parts.push((Part::Ground, total));
        for (i, b) in terrain.buildings.iter().enumerate() {
            let e = b.max - b.min;
            total += e.x * e.y;
            parts.push((Part::Roof(i), total));
            total += 2.0 * (e.x + e.y) * (b.roof - low);
            parts.push((Part::Wall(i), total));
        }
        Ok(TerrainSampler {
            terrain,
            parts,
            total,
            slope_factor_bound,
            low,
            w_max: terrain.density_ratio,
        })
    }

    fn pick_part(&self, rng: &mut Rng) -> Part {
        let u = rng.uniform() * self.total;
        let i = self.parts.partition_point(|&(_, c)| c <= u);
        self.parts[i.min(self.parts.len() - 1)].0
    }

    /// One proposal; `None` when rejected.
    fn propose(&self, rng: &mut Rng) -> Option<Sample> {
        let t = self.terrain;
        let half = t.side * 0.5;
        let (sample, accept) = match self.pick_part(rng) {
            Part::Ground => {
                let x = rng.range(-half, half);
                let y = rng.range(-half, half);
                if t.in_footprint(x, y) {
                    return None;
                }
                let (z, g) = t.height(x, y);
                let n = DVec3::new(-g.x, -g.y, 1.0);
                let s = Sample {
                    p: DVec3::new(x, y, z),
                    n: n / n.length(),
                };
                (s, n.length() / self.slope_factor_bound)
            }
            Part::Roof(i) => {
                let b = &t.buildings[i];
                let x = rng.range(b.min.x, b.max.x);
                let y = rng.range(b.min.y, b.max.y);
                let p = DVec3::new(x, y, b.roof);
                (Sample { p, n: DVec3::Z }, 1.0)
            }
            Part::Wall(i) => {
                let (x, y, n) = wall_point(&t.buildings[i], rng);
                let z = rng.range(self.low, t.buildings[i].roof);
                if z < t.height(x, y).0 {
                    return None;
                }
                (
                    Sample {
                        p: DVec3::new(x, y, z),
                        n,
                    },
                    1.0,
                )
            }
        };
        let accept = accept * t.density_weight(sample.p.x) / self.w_max;
        (rng.uniform() < accept).then_some(sample)
    }

    /// Integrals `(int w dA, int sqrt(w) dA, area)` by the midpoint rule
    /// (`GRID` cells per side of the square, `GRID` steps per wall edge).
    fn integrals(&self) -> (f64, f64, f64) {
        const GRID: usize = 400;
        let t = self.terrain;
        let half = t.side * 0.5;
        let h = t.side / GRID as f64;
        let mut acc = [0.0; 3];
        let mut add = |x: f64, da: f64| {
            let w = t.density_weight(x);
            acc[0] += w * da;
            acc[1] += w.sqrt() * da;
            acc[2] += da;
        };
        for i in 0..GRID {
            let x = -half + (i as f64 + 0.5) * h;
            for j in 0..GRID {
                let y = -half + (j as f64 + 0.5) * h;
                if !t.in_footprint(x, y) {
                    add(x, t.height(x, y).1.length().hypot(1.0) * h * h);
                }
            }
        }
        for b in &t.buildings {
            for_footprint_cells(b, GRID, &mut |x, da| add(x, da));
            for_wall_steps(b, GRID, &mut |x, y, ds| {
                add(x, (b.roof - t.height(x, y).0) * ds)
            });
        }
        (acc[0], acc[1], acc[2])
    }
}

/// Uniform point on the perimeter of `b`'s footprint, with the outward
/// horizontal normal of its wall.
fn wall_point(b: &Building, rng: &mut Rng) -> (f64, f64, DVec3) {
    let e = b.max - b.min;
    let s = rng.uniform() * 2.0 * (e.x + e.y);
    if s < e.x {
        (b.min.x + s, b.min.y, DVec3::NEG_Y)
    } else if s < e.x + e.y {
        (b.max.x, b.min.y + (s - e.x), DVec3::X)
    } else if s < 2.0 * e.x + e.y {
        (b.max.x - (s - e.x - e.y), b.max.y, DVec3::Y)
    } else {
        (b.min.x, b.max.y - (s - 2.0 * e.x - e.y), DVec3::NEG_X)
    }
}

fn for_footprint_cells(b: &Building, grid: usize, f: &mut dyn FnMut(f64, f64)) {
    // The density depends on x only, so strips across y suffice.
    let e = b.max - b.min;
    let dx = e.x / grid as f64;
    for i in 0..grid {
        f(b.min.x + (i as f64 + 0.5) * dx, e.y * dx);
    }
}

fn for_wall_steps(b: &Building, steps: usize, f: &mut dyn FnMut(f64, f64, f64)) {
    let e = b.max - b.min;
    let (dx, dy) = (e.x / steps as f64, e.y / steps as f64);
    for i in 0..steps {
        let x = b.min.x + (i as f64 + 0.5) * dx;
        let y = b.min.y + (i as f64 + 0.5) * dy;
        f(x, b.min.y, dx);
        f(x, b.max.y, dx);
        f(b.min.x, y, dy);
        f(b.max.x, y, dy);
    }
}

impl Sampler for TerrainSampler<'_> {
    fn sample(&self, rng: &mut Rng) -> Sample {
        loop {
            if let Some(s) = self.propose(rng) {
                return s;
            }
        }
    }
    fn area(&self) -> f64 {
        self.integrals().2
    }
    /// `(int sqrt(f) dA)^2` with `f = w / int w dA`.
    fn spacing_area(&self) -> f64 {
        let (w, root_w, _) = self.integrals();
        root_w * root_w / w
    }
}
