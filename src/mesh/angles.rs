//! Triangle shape quality for `scanmesh eval`: the smallest corner angle of
//! each triangle, as a histogram in 5-degree bins (0..60, the largest a
//! smallest angle can be), its mean, and the share below 10 degrees (a
//! sliver, the figure peers quote: CGAL's advancing front leaves 5.1 % on
//! the 1M dragon).
//!
//! Angles come from `atan2(|u x v|, u . v)`, accurate for tiny and
//! near-straight angles alike. Triangles with an out-of-range index, a
//! non-finite corner or a repeated index have no angles and are left out;
//! a zero-area triangle with distinct indices has a smallest angle of 0
//! and counts as a sliver (a zero-length edge gives its corners angle 0).

use super::Mesh;
use glam::DVec3;
use rayon::prelude::*;
use std::fmt;

/// Width of a histogram bin, degrees.
pub(crate) const BIN_DEGREES: f64 = 5.0;
/// Bins: 0-5, 5-10, ..., 55-60 (60 itself, an equilateral, in the last).
pub(crate) const BINS: usize = 12;
/// A triangle whose smallest angle is below this is a sliver.
pub(crate) const SLIVER_DEGREES: f64 = 10.0;

/// Triangles per parallel chunk; fixed so float sums are reproducible.
const CHUNK: usize = 1 << 16;

/// The distribution of the triangles' smallest angles: how far a mesh is from slivers.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct AngleReport {
    /// Triangles measured.
    pub triangles: u64,
    /// Count per `BIN_DEGREES` bin of the smallest angle.
    pub min_angle_histogram: [u64; BINS],
    /// Smallest angle below `SLIVER_DEGREES`.
    pub slivers: u64,
    /// `slivers / triangles` (0 for no triangle).
    pub sliver_share: f64,
    /// Mean of the triangles' smallest angles, in degrees (0 for no triangle).
    pub mean_min_angle_deg: f64,
    /// The smallest angle of the whole mesh (`None` for no triangle).
    pub smallest_angle_deg: Option<f64>,
}

/// Smallest corner angle of triangle `abc`, degrees (0 for a zero-length
/// edge).
pub fn min_angle_deg(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let corner = |p: DVec3, q: DVec3, r: DVec3| {
        let (u, v) = (q - p, r - p);
        if u == DVec3::ZERO || v == DVec3::ZERO {
            0.0
        } else {
            u.cross(v).length().atan2(u.dot(v))
        }
    };
    corner(a, b, c)
        .min(corner(b, c, a))
        .min(corner(c, a, b))
        .to_degrees()
}

#[derive(Clone, Copy, Default)]
struct Partial {
    histogram: [u64; BINS],
    slivers: u64,
    sum: f64,
    smallest: f64,
}

/// Smallest-angle statistics of `mesh`. Deterministic (fixed chunks summed
/// in order).
pub fn angle_report(mesh: &Mesh) -> AngleReport {
    let parts: Vec<Partial> = mesh
        .triangles
        .par_chunks(CHUNK)
        .map(|chunk| {
            let mut p = Partial {
                smallest: f64::INFINITY,
                ..Partial::default()
            };
            for &t in chunk {
                if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
                    continue;
                }
                let Some([a, b, c]) = mesh.corners(t) else {
                    continue;
                };
                let angle = min_angle_deg(a, b, c);
                let bin = ((angle / BIN_DEGREES) as usize).min(BINS - 1);
                p.histogram[bin] += 1;
                p.slivers += u64::from(angle < SLIVER_DEGREES);
                p.sum += angle;
                p.smallest = p.smallest.min(angle);
            }
            p
        })
        .collect();
    let mut total = Partial {
        smallest: f64::INFINITY,
        ..Partial::default()
    };
    for p in parts {
        for (t, x) in total.histogram.iter_mut().zip(p.histogram) {
            *t += x;
        }
        total.slivers += p.slivers;
        total.sum += p.sum;
        total.smallest = total.smallest.min(p.smallest);
    }
    let n: u64 = total.histogram.iter().sum();
    let per = |x: f64| if n > 0 { x / n as f64 } else { 0.0 };
    AngleReport {
        triangles: n,
        min_angle_histogram: total.histogram,
        slivers: total.slivers,
        sliver_share: per(total.slivers as f64),
        mean_min_angle_deg: per(total.sum),
        smallest_angle_deg: (n > 0).then_some(total.smallest),
    }
}

impl fmt::Display for AngleReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "min angle         mean {:.2} deg, smallest {}, {} of {} triangles under {SLIVER_DEGREES} deg ({:.3} %)",
            self.mean_min_angle_deg,
            self.smallest_angle_deg
                .map_or("n/a".to_string(), |a| format!("{a:.3} deg")),
            self.slivers,
            self.triangles,
            100.0 * self.sliver_share
        )?;
        let bins: Vec<String> = self
            .min_angle_histogram
            .iter()
            .enumerate()
            .map(|(i, n)| format!("{}-{}:{n}", i * 5, i * 5 + 5))
            .collect();
        write!(f, "  histogram (deg) {}", bins.join(" "))
    }
}
