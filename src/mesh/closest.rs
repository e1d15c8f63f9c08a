//! Closest point on a triangle to a point: Ericson, "Real-Time Collision
//! Detection" (2005), section 5.1.5, region by region from barycentric
//! tests, with no division until the region is known.
//!
//! Deviation, for robustness: a (near-)degenerate triangle, whose normal is
//! below `DEGENERATE_SIN` of its edge lengths, has no reliable face region;
//! its closest point is taken on its three edges instead (section 5.1.2),
//! which is exact for a zero-area triangle.

use glam::DVec3;

/// Sine of the corner angle at `a` below which the triangle is treated as
/// a set of segments.
const DEGENERATE_SIN: f64 = 1e-12;

/// The point of triangle `abc` nearest to `p`.
pub fn closest_point_on_triangle(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> DVec3 {
    let (ab, ac) = (b - a, c - a);
    let n2 = ab.cross(ac).length_squared();
    if n2 <= DEGENERATE_SIN * DEGENERATE_SIN * ab.length_squared() * ac.length_squared() {
        return closest_on_edges(p, a, b, c);
    }
    let q = ericson_regions(p, a, b, c, ab, ac);
    if q.is_finite() {
        q
    } else {
        closest_on_edges(p, a, b, c)
    }
}

/// Squared distance from `p` to triangle `abc`.
pub fn point_triangle_distance2(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> f64 {
    (p - closest_point_on_triangle(p, a, b, c)).length_squared()
}

fn ericson_regions(p: DVec3, a: DVec3, b: DVec3, c: DVec3, ab: DVec3, ac: DVec3) -> DVec3 {
    let ap = p - a;
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a; // vertex region A
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b; // vertex region B
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3)); // edge region AB
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c; // vertex region C
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6)); // edge region AC
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return b + (c - b) * w; // edge region BC
    }
    let denom = 1.0 / (va + vb + vc);
    a + ab * (vb * denom) + ac * (vc * denom) // face region
}

/// Closest point on segment `ab` (Ericson section 5.1.2); a zero-length
/// segment is its point.
pub fn closest_point_on_segment(p: DVec3, a: DVec3, b: DVec3) -> DVec3 {
    let ab = b - a;
    let len2 = ab.length_squared();
    if len2 <= 0.0 {
        return a;
    }
    let t = ((p - a).dot(ab) / len2).clamp(0.0, 1.0);
    a + ab * t
}

/// Squared distance between segments `p1q1` and `p2q2` (Ericson section
/// 5.1.9: the closest parameters on the two lines, clamped to the segments
/// one after the other); a zero-length segment is its point.
pub fn segment_segment_distance2(p1: DVec3, q1: DVec3, p2: DVec3, q2: DVec3) -> f64 {
    let (d1, d2, r) = (q1 - p1, q2 - p2, p1 - p2);
    let (a, e, f) = (d1.length_squared(), d2.length_squared(), d2.dot(r));
    let (s, t) = if a <= 0.0 && e <= 0.0 {
        (0.0, 0.0)
    } else if a <= 0.0 {
        (0.0, (f / e).clamp(0.0, 1.0))
    } else {
        let c = d1.dot(r);
        if e <= 0.0 {
            ((-c / a).clamp(0.0, 1.0), 0.0)
        } else {
            let b = d1.dot(d2);
            let denom = a * e - b * b;
            // Parallel segments (denom 0): any s; take the start.
            let s = if denom > 0.0 {
                ((b * f - c * e) / denom).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let t = (b * s + f) / e;
            if t < 0.0 {
                ((-c / a).clamp(0.0, 1.0), 0.0)
            } else if t > 1.0 {
                (((b - c) / a).clamp(0.0, 1.0), 1.0)
            } else {
                (s, t)
            }
        }
    };
    ((p1 + d1 * s) - (p2 + d2 * t)).length_squared()
}

fn closest_on_edges(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> DVec3 {
    let candidates = [
        closest_point_on_segment(p, a, b),
        closest_point_on_segment(p, b, c),
        closest_point_on_segment(p, c, a),
    ];
    let mut best = candidates[0];
    for q in &candidates[1..] {
        if (p - *q).length_squared() < (p - best).length_squared() {
            best = *q;
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    const A: DVec3 = DVec3::new(0.0, 0.0, 0.0);
    const B: DVec3 = DVec3::new(2.0, 0.0, 0.0);
    const C: DVec3 = DVec3::new(0.0, 2.0, 0.0);

    #[test]
    fn each_region_has_its_known_answer() {
        let cases = [
            (DVec3::new(0.5, 0.5, 3.0), DVec3::new(0.5, 0.5, 0.0)), // face
            (DVec3::new(-1.0, -1.0, 1.0), A),                       // vertex A
            (DVec3::new(3.0, -1.0, 0.0), B),                        // vertex B
            (DVec3::new(-1.0, 3.0, 0.0), C),                        // vertex C
            (DVec3::new(1.0, -2.0, 0.0), DVec3::new(1.0, 0.0, 0.0)), // edge AB
            (DVec3::new(-2.0, 1.0, 5.0), DVec3::new(0.0, 1.0, 0.0)), // edge AC
            (DVec3::new(2.0, 2.0, 0.0), DVec3::new(1.0, 1.0, 0.0)), // edge BC
        ];
        for (p, want) in cases {
            let got = closest_point_on_triangle(p, A, B, C);
            assert!(
                (got - want).length() < 1e-15,
                "p {p}: got {got}, want {want}"
            );
        }
    }

    #[test]
    fn segment_distances_against_sampled_minima() {
        let v = DVec3::new;
        let cases = [
            // Crossing at right angles, 1 apart in z.
            (
                [v(-1., 0., 0.), v(1., 0., 0.), v(0., -1., 1.), v(0., 1., 1.)],
                1.0,
            ),
            // Parallel, overlapping, 0.5 apart.
            (
                [v(0., 0., 0.), v(2., 0., 0.), v(1., 0.5, 0.), v(3., 0.5, 0.)],
                0.25,
            ),
            // End to end along a line.
            (
                [v(0., 0., 0.), v(1., 0., 0.), v(3., 0., 0.), v(4., 0., 0.)],
                4.0,
            ),
            // A point against a segment.
            (
                [v(0., 2., 0.), v(0., 2., 0.), v(-1., 0., 0.), v(1., 0., 0.)],
                4.0,
            ),
        ];
        for ([p1, q1, p2, q2], want) in cases {
            let got = segment_segment_distance2(p1, q1, p2, q2);
            assert!((got - want).abs() < 1e-12, "{p1} {q1} {p2} {q2}: {got}");
            let sampled = (0..=100)
                .flat_map(|i| (0..=100).map(move |j| (i as f64 / 100.0, j as f64 / 100.0)))
                .map(|(s, t)| (p1.lerp(q1, s) - p2.lerp(q2, t)).length_squared())
                .fold(f64::INFINITY, f64::min);
            assert!(got <= sampled + 1e-12, "sampled {sampled} below {got}");
        }
    }

    #[test]
    fn degenerate_triangles_fall_back_to_segments() {
        let (a, b, c) = (A, B, DVec3::new(1.0, 0.0, 0.0));
        let got = closest_point_on_triangle(DVec3::new(1.5, 1.0, 0.0), a, b, c);
        assert_eq!(got, DVec3::new(1.5, 0.0, 0.0));
        let got = closest_point_on_triangle(DVec3::new(1.0, 1.0, 1.0), a, a, a);
        assert_eq!(got, a);
    }
}
