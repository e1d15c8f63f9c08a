//! Seeded pseudo-random numbers (bottom layer): xoshiro256** seeded by
//! SplitMix64, plus the few continuous distributions the synthetic scans
//! (`synth`) and the mesh samplers (`mesh::sampling`) need; below them both,
//! so no production module imports the test-data generators for it.
//!
//! Algorithms: xoshiro256** and SplitMix64 from Blackman & Vigna, "Scrambled
//! linear pseudorandom number generators" (ACM TOMS 2021); Gaussian by
//! Marsaglia's polar method (1964); directions on the sphere by Marsaglia
//! (1972). None of the five scanmesh papers covers test-data generation.
//!
//! Cross-platform determinism: every draw uses only integer operations,
//! IEEE-754 `+ - * /` and `sqrt` (all correctly rounded, and Rust never fuses
//! them into FMAs), so the streams are bit-identical on every platform.
//! The polar method needs a logarithm, and platform `libm`s may differ in the
//! last ulp, so [`portable_ln`] computes it from basic operations.

use glam::DVec3;

/// Small, fast, seeded generator (xoshiro256**). Not cryptographic.
#[derive(Clone, Debug)]
pub struct Rng {
    s: [u64; 4],
    /// The polar method makes Gaussians in pairs; the second waits here.
    spare_normal: Option<f64>,
}

/// One step of SplitMix64; used only to expand a 64-bit seed into state.
fn splitmix64(state: &mut u64) -> u64 {
    *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

impl Rng {
    /// A generator whose whole stream is fixed by `seed`. SplitMix64 never
    /// yields the all-zero xoshiro state, so every seed (including 0) is valid.
    pub fn new(seed: u64) -> Self {
        let mut sm = seed;
        let s = [
            splitmix64(&mut sm),
            splitmix64(&mut sm),
            splitmix64(&mut sm),
            splitmix64(&mut sm),
        ];
        Rng {
            s,
            spare_normal: None,
        }
    }

    /// Next 64 uniformly distributed bits.
    pub fn next_u64(&mut self) -> u64 {
        let result = self.s[1].wrapping_mul(5).rotate_left(7).wrapping_mul(9);
        let t = self.s[1] << 17;
        self.s[2] ^= self.s[0];
        self.s[3] ^= self.s[1];
        self.s[1] ^= self.s[2];
        self.s[0] ^= self.s[3];
        self.s[2] ^= t;
        self.s[3] = self.s[3].rotate_left(45);
        result
    }

    /// Uniform in `[0, 1)` with 53 random bits (every multiple of 2^-53).
    pub fn uniform(&mut self) -> f64 {
        const SCALE: f64 = 1.0 / (1u64 << 53) as f64;
        (self.next_u64() >> 11) as f64 * SCALE
    }

    /// Uniform in `[a, b)` (for `a < b`; `a` when `a == b`).
    pub fn range(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.uniform()
    }

    /// Uniform integer in `0..n` by Lemire's multiply-shift (with its
    /// rejection step, so it is exactly uniform). Returns 0 when `n == 0`.
    pub fn below(&mut self, n: u64) -> u64 {
        if n == 0 {
            return 0;
        }
        let threshold = n.wrapping_neg() % n;
        loop {
            let m = u128::from(self.next_u64()) * u128::from(n);
            if (m as u64) >= threshold {
                return (m >> 64) as u64;
            }
        }
    }

    /// Standard normal deviate (mean 0, variance 1), Marsaglia polar method.
    pub fn normal(&mut self) -> f64 {
        if let Some(z) = self.spare_normal.take() {
            return z;
        }
        loop {
            let u = self.range(-1.0, 1.0);
            let v = self.range(-1.0, 1.0);
            let s = u * u + v * v;
            if s > 0.0 && s < 1.0 {
                let factor = (-2.0 * portable_ln(s) / s).sqrt();
                self.spare_normal = Some(v * factor);
                return u * factor;
            }
        }
    }

    /// Point uniformly distributed on the unit circle, as `(cos t, sin t)`,
    /// by rejection from the square (no trigonometry, hence portable).
    pub fn unit_circle(&mut self) -> (f64, f64) {
        loop {
            let x = self.range(-1.0, 1.0);
            let y = self.range(-1.0, 1.0);
            let r2 = x * x + y * y;
            // The lower bound keeps the division well conditioned.
            if r2 > 1e-12 && r2 <= 1.0 {
                let r = r2.sqrt();
                return (x / r, y / r);
            }
        }
    }

    /// Direction uniformly distributed on the unit sphere (Marsaglia 1972).
    pub fn unit_vector(&mut self) -> DVec3 {
        loop {
            let x1 = self.range(-1.0, 1.0);
            let x2 = self.range(-1.0, 1.0);
            let s = x1 * x1 + x2 * x2;
            if s < 1.0 {
                let w = 2.0 * (1.0 - s).sqrt();
                let v = DVec3::new(x1 * w, x2 * w, 1.0 - 2.0 * s);
                // |v| = 1 analytically; renormalise away the rounding.
                return v / v.length();
            }
        }
    }

    /// Isotropic Gaussian vector with standard deviation `sigma` per axis.
    pub fn gaussian_vector(&mut self, sigma: f64) -> DVec3 {
        DVec3::new(self.normal(), self.normal(), self.normal()) * sigma
    }
}

/// Natural logarithm from basic IEEE operations only, so results do not
/// depend on the platform's `libm`. Accurate to a few ulp for positive finite
/// `x`; returns NaN for `x <= 0` or non-finite `x` (the generators never ask).
///
/// Method: `x = m * 2^e` with `m` in `[sqrt(1/2), sqrt(2))`, then
/// `ln m = 2 atanh(s)`, `s = (m - 1) / (m + 1)`, `|s| <= 0.172`, by its odd
/// power series (13 terms reach below 2^-53 relative).
pub fn portable_ln(x: f64) -> f64 {
    if !(x > 0.0 && x.is_finite()) {
        return f64::NAN;
    }
    let (x, bias) = if x < f64::MIN_POSITIVE {
        // Subnormal: scale into the normal range first.
        (x * (1u64 << 54) as f64, -54)
    } else {
        (x, 0)
    };
    let bits = x.to_bits();
    let mut e = ((bits >> 52) & 0x7ff) as i64 - 1023 + bias;
    let mut m = f64::from_bits((bits & 0x000f_ffff_ffff_ffff) | (1023u64 << 52));
    if m > std::f64::consts::SQRT_2 {
        m *= 0.5;
        e += 1;
    }
    let s = (m - 1.0) / (m + 1.0);
    let s2 = s * s;
    let mut series = 0.0;
    for k in (0..13).rev() {
        series = series * s2 + 1.0 / (2 * k + 1) as f64;
    }
    e as f64 * std::f64::consts::LN_2 + 2.0 * s * series
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn xoshiro_reference_stream() {
        // Reference values of the C reference implementation (xoshiro256**
        // with state {1, 2, 3, 4}).
        let mut r = Rng {
            s: [1, 2, 3, 4],
            spare_normal: None,
        };
        let got: Vec<u64> = (0..4).map(|_| r.next_u64()).collect();
        assert_eq!(
            got,
            vec![11520, 0, 1509978240, 1215971899390074240],
            "xoshiro256** diverges from the reference"
        );
    }

    #[test]
    fn splitmix_reference() {
        // SplitMix64 from seed 0: first output of the reference implementation.
        let mut s = 0u64;
        assert_eq!(splitmix64(&mut s), 0xE220_A839_7B1D_CDAF);
    }

    #[test]
    fn portable_ln_matches_std() {
        let mut r = Rng::new(7);
        for _ in 0..100_000 {
            let x = r.uniform() * 10f64.powi((r.below(40) as i32) - 20) + 1e-300;
            let want = x.ln();
            let got = portable_ln(x);
            let tol = 4.0 * f64::EPSILON * want.abs().max(1.0);
            assert!((got - want).abs() <= tol, "x={x:e}: {got} vs {want}");
        }
        assert_eq!(portable_ln(1.0), 0.0);
        assert!(portable_ln(0.0).is_nan() && portable_ln(-1.0).is_nan());
        let tiny = 5e-324_f64;
        assert!((portable_ln(tiny) - tiny.ln()).abs() < 1e-12);
    }

    #[test]
    fn uniform_and_normal_moments() {
        let seed = 42;
        let mut r = Rng::new(seed);
        let n = 200_000;
        let (mut su, mut sn, mut sn2) = (0.0, 0.0, 0.0);
        for _ in 0..n {
            let u = r.uniform();
            assert!((0.0..1.0).contains(&u));
            su += u;
            let z = r.normal();
            sn += z;
            sn2 += z * z;
        }
        let nf = n as f64;
        assert!((su / nf - 0.5).abs() < 0.005, "seed {seed}: uniform mean");
        assert!((sn / nf).abs() < 0.01, "seed {seed}: normal mean");
        assert!(
            (sn2 / nf - 1.0).abs() < 0.015,
            "seed {seed}: normal variance"
        );
    }

    #[test]
    fn below_is_in_range_and_covers() {
        let mut r = Rng::new(3);
        let mut seen = [0u32; 7];
        for _ in 0..7000 {
            seen[r.below(7) as usize] += 1;
        }
        assert!(seen.iter().all(|&c| c > 850 && c < 1150), "{seen:?}");
        assert_eq!(r.below(0), 0);
    }

    #[test]
    fn unit_vectors_are_unit_and_centred() {
        let mut r = Rng::new(11);
        let mut sum = DVec3::ZERO;
        for _ in 0..100_000 {
            let v = r.unit_vector();
            assert!((v.length() - 1.0).abs() < 1e-15);
            sum += v;
            let (c, s) = r.unit_circle();
            assert!((c * c + s * s - 1.0).abs() < 1e-15);
        }
        assert!(sum.length() / 100_000.0 < 0.01);
    }
}
