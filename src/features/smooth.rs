//! Adaptive smoothing of the enhanced feature points (paper 5 section 4):
//! each point's neighbours within `delta` (enhanced points of its kind),
//! `delta` grown by a fixed factor until their distribution is elongated
//! enough (`|rho| >= 0.6`), then the point projected onto their principal
//! axis; a point that never gets there is noise and is dropped.
//!
//! The correlation coefficient: the paper projects the neighbours into the
//! plane of the two largest principal directions and takes the correlation
//! of their two coordinates in some `(u, v)` axes of that plane. In the
//! principal axes themselves that correlation is zero by construction, and
//! in arbitrary axes it depends on their rotation; Lee's curve
//! reconstruction (the paper's reference \[15\]) measures it in axes at 45
//! degrees to the principal one, where it equals `(l0 - l1) / (l0 + l1)`
//! for the two largest covariance eigenvalues `l0 >= l1`: `|rho| >= 0.6`
//! means the neighbourhood is at least four times longer than wide. That
//! is what we compute.
//!
//! Corners (section 4: "if a corner enters the neighbourhood, the corner
//! and the points that may belong to other lines are removed"): with a
//! corner `c` within `delta`, only the neighbours within 45 degrees of the
//! direction from `c` to the point are kept (lines meeting at a corner
//! leave it in other directions). Corners themselves are not
//! smoothed (deviation): where lines meet the neighbourhood is never
//! elongated, so the test would call every corner noise.

use crate::normals::eigen::sym3_eigen;
use crate::spatial::Neighbour;
use glam::DVec3;

/// Section 4's thresholds.
#[derive(Clone, Copy, Debug)]
pub struct SmoothParams {
    pub delta: f64,
    pub growth: f64,
    pub delta_max: f64,
    pub rho: f64,
}

/// `(l0 - l1) / (l0 + l1)` of the two largest covariance eigenvalues of
/// `pts` (0 when they do not spread), and the principal axis and centroid.
pub fn elongation(pts: &[DVec3]) -> (f64, DVec3, DVec3) {
    let Some(&anchor) = pts.first() else {
        return (0.0, DVec3::X, DVec3::ZERO);
    };
    let n = pts.len() as f64;
    let offset = pts.iter().fold(DVec3::ZERO, |s, p| s + (*p - anchor)) / n;
    let mut m = [[0.0f64; 3]; 3];
    for p in pts {
        let d = (*p - anchor) - offset;
        for (r, row) in m.iter_mut().enumerate() {
            for (c, cell) in row.iter_mut().enumerate() {
                *cell += d[r] * d[c];
            }
        }
    }
    let (vals, vecs) = sym3_eigen(m);
    let (l0, l1) = (vals[2].max(0.0), vals[1].max(0.0));
    let rho = if l0 + l1 > 0.0 {
        (l0 - l1) / (l0 + l1)
    } else {
        0.0
    };
    (rho, vecs[2], anchor + offset)
}

/// What the smoothing makes of a point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Smoothed {
    /// Projected onto its neighbours' principal axis.
    At(DVec3),
    /// Never elongated enough up to `delta_max`: noise.
    Noise,
    /// Needs neighbours beyond the radius they were gathered within.
    Wider,
}

/// The smoothed position of the edge point `s`. `around` holds the
/// enhanced points of its kind within `within` of `s` (itself included)
/// in a canonical order (`spatial::ball`), `positions` their positions; `corners` the
/// kept corners of its kind within `within`. Most points settle at the
/// first radius, so callers gather that first and ask again with
/// `delta_max` on [`Smoothed::Wider`].
pub fn smooth_point(
    s: DVec3,
    around: &[Neighbour],
    within: f64,
    positions: &[DVec3],
    corners: &[DVec3],
    p: &SmoothParams,
    buf: &mut Vec<DVec3>,
) -> Smoothed {
    let mut delta = p.delta;
    loop {
        if delta > within {
            return Smoothed::Wider;
        }
        let r2 = delta * delta;
        buf.clear();
        let near_corners: Vec<DVec3> = corners
            .iter()
            .copied()
            .filter(|c| c.distance_squared(s) <= r2 && *c != s)
            .collect();
        for n in around.iter().filter(|n| n.dist2 <= r2) {
            let q = positions[n.index as usize];
            // Other lines leave a corner in other directions.
            let same_line = |c: &DVec3| {
                let (a, b) = (q - *c, s - *c);
                a.dot(b) > std::f64::consts::FRAC_1_SQRT_2 * (a.length() * b.length())
            };
            if near_corners.iter().all(same_line) {
                buf.push(q);
            }
        }
        if buf.len() >= 3 {
            let (rho, axis, centre) = elongation(buf);
            if rho >= p.rho {
                return Smoothed::At(centre + axis * (s - centre).dot(axis));
            }
        }
        if delta >= p.delta_max {
            return Smoothed::Noise;
        }
        delta = (delta * p.growth).min(p.delta_max);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    fn params() -> SmoothParams {
        SmoothParams {
            delta: 0.1,
            growth: 1.25,
            delta_max: 0.4,
            rho: 0.6,
        }
    }

    fn hood(s: DVec3, pts: &[DVec3]) -> Vec<Neighbour> {
        let mut v: Vec<Neighbour> = pts
            .iter()
            .enumerate()
            .map(|(i, p)| Neighbour {
                dist2: p.distance_squared(s),
                index: i as u32,
            })
            .filter(|n| n.dist2 <= 0.16)
            .collect();
        v.sort_by(|a, b| a.dist2.total_cmp(&b.dist2).then(a.index.cmp(&b.index)));
        v
    }

    #[test]
    fn points_near_a_line_move_onto_it_and_blobs_are_noise() {
        let mut rng = Rng::new(2);
        let pts: Vec<DVec3> = (0..200)
            .map(|_| DVec3::new(rng.range(-1.0, 1.0), rng.range(-0.02, 0.02), 0.0))
            .collect();
        let mut buf = Vec::new();
        for s in pts.iter().take(20).filter(|s| s.x.abs() < 0.5) {
            let Smoothed::At(out) =
                smooth_point(*s, &hood(*s, &pts), 0.4, &pts, &[], &params(), &mut buf)
            else {
                panic!("{s} not smoothed");
            };
            assert!(
                out.y.abs() < 0.01 && (out.x - s.x).abs() < 0.01,
                "{s} -> {out}"
            );
        }
        let blob: Vec<DVec3> = (0..100).map(|_| rng.unit_vector() * 0.05).collect();
        let s = blob[0];
        assert_eq!(
            smooth_point(s, &hood(s, &blob), 0.4, &blob, &[], &params(), &mut buf),
            Smoothed::Noise
        );
        // Gathered within the first radius only: ask for more.
        assert_eq!(
            smooth_point(s, &hood(s, &blob), 0.1, &blob, &[], &params(), &mut buf),
            Smoothed::Wider
        );
    }

    #[test]
    fn a_corner_keeps_the_other_line_out() {
        // An L: along +x and along +y, corner at the origin.
        let mut pts: Vec<DVec3> = (1..40)
            .map(|i| DVec3::new(i as f64 * 0.01, 0.0, 0.0))
            .collect();
        pts.extend((1..40).map(|i| DVec3::new(0.0, i as f64 * 0.01, 0.0)));
        let s = DVec3::new(0.05, 0.003, 0.0);
        let mut buf = Vec::new();
        let p = SmoothParams {
            delta: 0.2,
            ..params()
        };
        let Smoothed::At(with) =
            smooth_point(s, &hood(s, &pts), 0.4, &pts, &[DVec3::ZERO], &p, &mut buf)
        else {
            panic!("not smoothed");
        };
        assert!(with.y.abs() < 1e-9, "{with}");
    }
}
