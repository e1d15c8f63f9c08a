//! The Fibonacci sphere: `n` nearly evenly spread points on a sphere, in a
//! spiral order, deterministic without a seed. Benches and tests use it where
//! a uniform, noise-free surface with a known normal is wanted.

use glam::DVec3;

/// Point `i` of `n` on the unit sphere (golden-angle spiral, z from +1 to -1).
pub fn fibonacci_direction(i: usize, n: usize) -> DVec3 {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    let z = 1.0 - (2 * i + 1) as f64 / n as f64;
    let r = (1.0 - z * z).sqrt();
    let phi = golden * i as f64;
    DVec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// `n` points on the sphere of `radius` around `centre`.
pub fn fibonacci_sphere(centre: DVec3, radius: f64, n: usize) -> Vec<DVec3> {
    (0..n)
        .map(|i| centre + radius * fibonacci_direction(i, n))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points_lie_on_the_sphere_and_balance() {
        let c = DVec3::new(5.0e5, 4.2e6, 100.0);
        let pts = fibonacci_sphere(c, 2.0, 1000);
        assert!(pts.iter().all(|p| ((*p - c).length() - 2.0).abs() < 1e-9));
        let mean = pts.iter().map(|p| *p - c).sum::<DVec3>() / 1000.0;
        assert!(mean.length() < 0.01, "{mean}");
    }
}
