//! Weighted quadratic curves in a support plane (paper 5 section 3,
//! formulas (4)-(5)): `y = a + b x + c x^2` fitted to a curve-fitting set,
//! weights the points' curvatures, plus the two queries the enhancement
//! needs: the point of a curve nearest to a given point, and where two
//! curves cross.
//!
//! Deviations, named:
//! - The paper fits `y = f(x)` in the plane's own `(u, v)` axes, which fails
//!   for a curve running along `v` (no function of `u`). We fit in the
//!   set's own axes: `x` along its weighted principal direction, `y` across.
//! - The paper minimises weighted squared distances to the curve (formula
//!   (4)), a nonlinear problem; in the set's own axes the vertical residual
//!   `y - f(x)` is that distance to first order, and the weighted linear
//!   least squares is what we solve.

use glam::DVec2;

/// A fitted curve: `origin + x t + f(x) n` for `x` in `[lo, hi]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Curve {
    origin: DVec2,
    t: DVec2,
    n: DVec2,
    coef: [f64; 3],
    pub lo: f64,
    pub hi: f64,
}

impl Curve {
    /// Fits the points `q[i]` with weights `w[i]` (positive) for `i` in
    /// `set`; `None` when the set is less elongated than `elongation`
    /// (`(l0 - l1) / (l0 + l1)` of its weighted covariance's eigenvalues) or
    /// the 3x3 system is singular.
    pub fn fit(q: &[DVec2], w: &[f64], set: &[usize], elongation: f64) -> Option<Curve> {
        let total: f64 = set.iter().map(|&i| w[i]).sum();
        if set.len() < 3 || total.is_nan() || total <= 0.0 {
            return None;
        }
        let origin = set.iter().map(|&i| q[i] * w[i]).sum::<DVec2>() / total;
        let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
        for &i in set {
            let d = q[i] - origin;
            sxx += w[i] * d.x * d.x;
            sxy += w[i] * d.x * d.y;
            syy += w[i] * d.y * d.y;
        }
        let spread = sxx + syy;
        let gap = ((sxx - syy) * (sxx - syy) + 4.0 * sxy * sxy).sqrt();
        if spread.is_nan() || spread <= 0.0 || gap < elongation * spread {
            return None;
        }
        // Major axis of the weighted 2x2 covariance.
        let angle = 0.5 * (2.0 * sxy).atan2(sxx - syy);
        let t = DVec2::new(angle.cos(), angle.sin());
        let n = t.perp();
        // The system is solved in coordinates scaled by the spread, so its
        // entries are O(1) whatever the units (x^4 of a 1e-3 set is 1e-12).
        let scale = spread.sqrt() / total.sqrt();
        let inv = 1.0 / scale;
        let mut m = [[0.0f64; 3]; 3];
        let mut rhs = [0.0f64; 3];
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for &i in set {
            let d = q[i] - origin;
            let (x, y) = (d.dot(t), d.dot(n));
            lo = lo.min(x);
            hi = hi.max(x);
            let (x, y) = (x * inv, y * inv);
            let b = [1.0, x, x * x];
            for r in 0..3 {
                rhs[r] += w[i] * b[r] * y;
                for c in 0..3 {
                    m[r][c] += w[i] * b[r] * b[c];
                }
            }
        }
        if (hi - lo).is_nan() || hi - lo <= 0.0 {
            return None;
        }
        let [a, b, c] = solve3(m, rhs)?;
        let coef = [a * scale, b, c * inv];
        Some(Curve {
            origin,
            t,
            n,
            coef,
            lo,
            hi,
        })
    }

    fn f(&self, x: f64) -> f64 {
        let [a, b, c] = self.coef;
        a + b * x + c * x * x
    }

    fn df(&self, x: f64) -> f64 {
        self.coef[1] + 2.0 * self.coef[2] * x
    }

    /// The curve's point at parameter `x`.
    pub fn at(&self, x: f64) -> DVec2 {
        self.origin + self.t * x + self.n * self.f(x)
    }

    /// The point of the curve (within its range) nearest to `p`, and the
    /// curve's unit tangent there.
    pub fn nearest(&self, p: DVec2) -> (DVec2, DVec2) {
        self.nearest_within(p, 0.0)
    }

    /// [`Curve::nearest`] over the range grown by `slack` at both ends.
    pub fn nearest_within(&self, p: DVec2, slack: f64) -> (DVec2, DVec2) {
        let (lo, hi) = (self.lo - slack, self.hi + slack);
        let d = p - self.origin;
        let (px, py) = (d.dot(self.t), d.dot(self.n));
        // Newton on the derivative of the squared distance, from the
        // projection; the curve is nearly straight over its range, so a few
        // steps converge. Then the better of that and the range's ends.
        let mut x = px.clamp(lo, hi);
        for _ in 0..8 {
            let (fx, dfx) = (self.f(x), self.df(x));
            let g = (x - px) + (fx - py) * dfx;
            let h = 1.0 + dfx * dfx + (fx - py) * 2.0 * self.coef[2];
            if h.is_nan() || h <= 0.0 {
                break;
            }
            let next = (x - g / h).clamp(lo, hi);
            if (next - x).abs() <= 1e-12 * (hi - lo) {
                x = next;
                break;
            }
            x = next;
        }
        let best = [x, lo, hi]
            .into_iter()
            .min_by(|a, b| {
                let (a, b) = (self.at(*a), self.at(*b));
                a.distance_squared(p).total_cmp(&b.distance_squared(p))
            })
            .unwrap_or(x);
        (self.at(best), self.tangent(best))
    }

    /// Signed offset of `p` from the curve, measured across it.
    fn offset(&self, p: DVec2) -> f64 {
        let d = p - self.origin;
        d.dot(self.n) - self.f(d.dot(self.t))
    }

    /// Unit tangent at parameter `x`.
    fn tangent(&self, x: f64) -> DVec2 {
        (self.t + self.n * self.df(x)).normalize()
    }

    /// Where this curve and `other` cross at an angle of at least
    /// `min_angle` (radians), each range grown by `slack`, the crossing
    /// nearest to `p`. Nearly parallel curves (two sets grown side by side
    /// in one wide band of feature points) cross at places that mean
    /// nothing; the angle test leaves them out.
    pub fn crossing(&self, other: &Curve, slack: f64, min_angle: f64, p: DVec2) -> Option<DVec2> {
        const SAMPLES: usize = 24;
        let (lo, hi) = (self.lo - slack, self.hi + slack);
        let sin_min = min_angle.sin();
        let within = |x_self: f64, c: DVec2| {
            let x = (c - other.origin).dot(other.t);
            let steep = self.tangent(x_self).perp_dot(other.tangent(x)).abs() >= sin_min;
            steep && x >= other.lo - slack && x <= other.hi + slack
        };
        let g = |x: f64| other.offset(self.at(x));
        let mut best: Option<DVec2> = None;
        let mut prev = (lo, g(lo));
        for s in 1..=SAMPLES {
            let x = lo + (hi - lo) * s as f64 / SAMPLES as f64;
            let cur = (x, g(x));
            if prev.1 == 0.0 || prev.1.signum() != cur.1.signum() {
                let x = bisect(&g, prev, cur);
                let c = self.at(x);
                let better = best.is_none_or(|b| c.distance_squared(p) < b.distance_squared(p));
                if within(x, c) && better {
                    best = Some(c);
                }
            }
            prev = cur;
        }
        best
    }
}

/// A root of `g` between `a` and `b` (opposite signs, or `a` a root).
fn bisect(g: &impl Fn(f64) -> f64, mut a: (f64, f64), mut b: (f64, f64)) -> f64 {
    if a.1 == 0.0 {
        return a.0;
    }
    for _ in 0..48 {
        let m = 0.5 * (a.0 + b.0);
        let gm = g(m);
        if gm == 0.0 {
            return m;
        }
        if gm.signum() == a.1.signum() {
            a = (m, gm);
        } else {
            b = (m, gm);
        }
    }
    0.5 * (a.0 + b.0)
}

/// Solves the symmetric 3x3 system by Gaussian elimination with partial
/// pivoting; `None` when singular (to rounding).
fn solve3(mut m: [[f64; 3]; 3], mut r: [f64; 3]) -> Option<[f64; 3]> {
    let scale = m.iter().flatten().fold(0.0f64, |a, v| a.max(v.abs()));
    for k in 0..3 {
        let p = (k..3).max_by(|&a, &b| m[a][k].abs().total_cmp(&m[b][k].abs()))?;
        let pivot = m[p][k].abs();
        if pivot.is_nan() || pivot <= 1e-12 * scale {
            return None;
        }
        m.swap(k, p);
        r.swap(k, p);
        let row = m[k];
        for i in k + 1..3 {
            let f = m[i][k] / row[k];
            for (a, b) in m[i][k..].iter_mut().zip(&row[k..]) {
                *a -= f * b;
            }
            r[i] -= f * r[k];
        }
    }
    let mut x = [0.0; 3];
    for i in (0..3).rev() {
        let s: f64 = (i + 1..3).map(|j| m[i][j] * x[j]).sum();
        x[i] = (r[i] - s) / m[i][i];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fits_a_parabola_along_v_and_finds_its_nearest_point() {
        // y-axis curve: u = 0.5 v^2, which y = f(u) in plane axes cannot fit.
        let q: Vec<DVec2> = (-10..=10)
            .map(|i| {
                let v = i as f64 * 0.1;
                DVec2::new(0.5 * v * v, v)
            })
            .collect();
        let w = vec![1.0; q.len()];
        let set: Vec<usize> = (0..q.len()).collect();
        let c = Curve::fit(&q, &w, &set, 0.6).unwrap();
        for p in &q {
            assert!(c.offset(*p).abs() < 1e-9, "{p}");
        }
        let (near, t) = c.nearest(DVec2::new(-0.3, 0.0));
        assert!(t.x.abs() < 1e-6, "{t}");
        assert!(near.distance(DVec2::ZERO) < 1e-6, "{near}");
    }

    #[test]
    fn tiny_units_fit_as_well_as_unit_ones() {
        for unit in [1.0, 1e-4, 1e4] {
            let q: Vec<DVec2> = (-10..=10)
                .map(|i| {
                    let x = i as f64 * 0.1;
                    DVec2::new(x, 0.3 * x * x + 0.1) * unit
                })
                .collect();
            let w = vec![2.0; q.len()];
            let set: Vec<usize> = (0..q.len()).collect();
            let c = Curve::fit(&q, &w, &set, 0.6).expect("fits at any unit");
            for p in &q {
                assert!(c.offset(*p).abs() < 1e-9 * unit, "unit {unit}: {p}");
            }
        }
    }

    #[test]
    fn two_lines_cross_at_their_corner() {
        let a: Vec<DVec2> = (0..10).map(|i| DVec2::new(i as f64 * 0.1, 0.0)).collect();
        let b: Vec<DVec2> = (0..10).map(|i| DVec2::new(0.0, i as f64 * 0.1)).collect();
        let w = vec![1.0; 10];
        let set: Vec<usize> = (0..10).collect();
        let ca = Curve::fit(&a, &w, &set, 0.6).unwrap();
        let cb = Curve::fit(&b, &w, &set, 0.6).unwrap();
        let x = ca.crossing(&cb, 0.05, 0.5, DVec2::new(0.2, 0.2)).unwrap();
        assert!(x.length() < 1e-9, "{x}");
        // Parallel lines never cross.
        let c: Vec<DVec2> = a.iter().map(|p| *p + DVec2::Y).collect();
        let cc = Curve::fit(&c, &w, &set, 0.6).unwrap();
        assert!(ca.crossing(&cc, 0.05, 0.5, DVec2::ZERO).is_none());
    }
}
