//! Area-uniform random points on a mesh, reproducible for a seed and
//! independent of the thread count: sample `i` draws from its own stream
//! (the project's [`crate::rng::Rng`] seeded by `seed` and `i`), picks a triangle in the cumulative
//! areas (stratified, see [`area_samples`]) and a point in it by the
//! square-root warp (Osada et al., "Shape distributions", 2002, section 4.2).

use super::Mesh;
use crate::rng::Rng;
use glam::DVec3;
use rayon::prelude::*;

/// Samples per parallel task: each task binary-searches once, then walks.
const TASK: usize = 4096;

/// `count` points distributed uniformly by area over the valid triangles of
/// `mesh`; empty when the mesh has no area. Stratified (jittered): sample
/// `i` falls in the `i`-th of `count` equal slices of the cumulative area,
/// so samples come in triangle order, spread more evenly than independent
/// draws, and are found by walking the cumulative areas instead of a
/// binary search per sample.
pub(crate) fn area_samples(mesh: &Mesh, count: usize, seed: u64) -> Vec<DVec3> {
    let cumulative = cumulative_areas(mesh);
    let total = cumulative.last().copied().unwrap_or(0.0);
    if count == 0 || total.is_nan() || total <= 0.0 {
        return Vec::new();
    }
    // The last triangle with area: the target when rounding lands on `total`.
    let last = cumulative
        .partition_point(|&c| c < total)
        .min(cumulative.len() - 1);
    let step = total / count as f64;
    (0..count.div_ceil(TASK))
        .into_par_iter()
        .flat_map_iter(|task| {
            let range = task * TASK..((task + 1) * TASK).min(count);
            let cumulative = &cumulative;
            // `t`: the first triangle whose running area exceeds `x`.
            let mut t: Option<usize> = None;
            range.filter_map(move |i| {
                let mut rng = Rng::new(seed ^ (i as u64).wrapping_mul(0xD6E8_FEB8_6659_FD93));
                let x = ((i as f64 + rng.uniform()) * step).min(total);
                let mut cur = match t {
                    Some(cur) => cur,
                    None => cumulative.partition_point(|&c| c <= x).min(last),
                };
                while cur < last && cumulative[cur] <= x {
                    cur += 1;
                }
                t = Some(cur);
                // A triangle that added area is valid, so this never skips.
                let [a, b, c] = mesh.corners(mesh.triangles[cur])?;
                let s = rng.uniform().sqrt();
                let r = rng.uniform();
                Some(a * (1.0 - s) + b * (s * (1.0 - r)) + c * (s * r))
            })
        })
        .collect()
}

/// Running sum of triangle areas in triangle order (invalid triangles add 0).
fn cumulative_areas(mesh: &Mesh) -> Vec<f64> {
    let mut sum = 0.0;
    mesh.triangles
        .iter()
        .map(|&t| {
            if let Some([a, b, c]) = mesh.corners(t) {
                sum += super::triangle_area(a, b, c);
            }
            sum
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_split_by_area_and_stay_on_their_triangle() {
        // Areas 1 (z = 0) and 3 (z = 5), plus an invalid triangle.
        let v = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
        let mesh = Mesh::new(
            vec![
                v(0., 0., 0.),
                v(2., 0., 0.),
                v(0., 1., 0.),
                v(0., 0., 5.),
                v(3., 0., 5.),
                v(0., 2., 5.),
            ],
            vec![[0, 1, 2], [0, 1, 9], [3, 4, 5]],
        );
        let samples = area_samples(&mesh, 10_000, 77);
        assert_eq!(samples.len(), 10_000);
        let low = samples.iter().filter(|p| p.z == 0.0).count();
        // Stratified: the split is exact up to the one straddling slice.
        assert!(
            (low as i64 - 2500).abs() <= 1,
            "seed 77: {low} of 10000 on the small triangle"
        );
        for p in &samples {
            let (w, h) = if p.z == 0.0 { (2.0, 1.0) } else { (3.0, 2.0) };
            assert!(
                p.x >= 0.0 && p.y >= 0.0 && p.x / w + p.y / h <= 1.0 + 1e-12,
                "seed 77: {p}"
            );
        }
        assert_eq!(area_samples(&mesh, 10, 1), area_samples(&mesh, 10, 1));
        assert!(area_samples(&Mesh::default(), 10, 1).is_empty());
    }
}
