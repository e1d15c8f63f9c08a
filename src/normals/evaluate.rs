//! Normals against a truth: angle errors and orientation agreement, as the
//! tests, benches and the demo report them.

use crate::store::{PointStore, StoreError, NORMALS};
use glam::DVec3;

/// Accuracy of computed normals against true ones.
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct NormalAccuracy {
    /// Points compared (both normals non-zero).
    pub compared: usize,
    /// Angle between the lines (sign ignored), degrees.
    pub median_angle_deg: f64,
    /// Nearest-rank 95th percentile of the angle between the lines, degrees.
    pub p95_angle_deg: f64,
    /// Fraction whose sign agrees with the truth (positive dot product).
    pub oriented_fraction: f64,
}

/// Compares `normals[i]` with `truth[i]`; zero normals (degenerate) are skipped.
pub fn accuracy(normals: &[DVec3], truth: &[DVec3]) -> NormalAccuracy {
    let mut angles = Vec::with_capacity(normals.len());
    let mut agree = 0usize;
    for (n, t) in normals.iter().zip(truth) {
        if *n == DVec3::ZERO || *t == DVec3::ZERO {
            continue;
        }
        let c = n.normalize().dot(t.normalize());
        angles.push(c.abs().clamp(0.0, 1.0).acos().to_degrees());
        agree += usize::from(c > 0.0);
    }
    if angles.is_empty() {
        return NormalAccuracy::default();
    }
    angles.sort_by(|a, b| a.total_cmp(b));
    let q = |f: f64| angles[((angles.len() - 1) as f64 * f).round() as usize];
    NormalAccuracy {
        compared: angles.len(),
        median_angle_deg: q(0.5),
        p95_angle_deg: q(0.95),
        oriented_fraction: agree as f64 / angles.len() as f64,
    }
}

/// Marks the points whose position is exactly shared by another point.
///
/// A reference mesh may hold a zero-thickness two-sided sheet as coincident
/// vertices whose normals point opposite ways (the Stanford dragon has 3,790
/// such vertices): no method that sees only positions can give them
/// different normals, so their flips are the reference's, and the report
/// shows the agreement with and without them.
pub fn coincident(points: &[DVec3]) -> Vec<bool> {
    let key = |i: &usize| points[*i].to_array().map(f64::to_bits);
    let mut order: Vec<usize> = (0..points.len()).collect();
    order.sort_unstable_by_key(key);
    let mut shared = vec![false; points.len()];
    for run in order.chunk_by(|a, b| key(a) == key(b)) {
        if run.len() > 1 {
            run.iter().for_each(|&i| shared[i] = true);
        }
    }
    shared
}

/// [`accuracy`] over the points where `keep` is true.
pub fn accuracy_where(normals: &[DVec3], truth: &[DVec3], keep: &[bool]) -> NormalAccuracy {
    let pick = |v: &[DVec3]| -> Vec<DVec3> {
        v.iter()
            .zip(keep)
            .filter(|(_, k)| **k)
            .map(|(n, _)| *n)
            .collect()
    };
    accuracy(&pick(normals), &pick(truth))
}

/// A store's normals in input order, in memory (evaluation of small
/// clouds only: 24 bytes per point).
pub fn normals_in_input_order(store: &PointStore) -> Result<Vec<DVec3>, StoreError> {
    let col = store.column(&NORMALS)?;
    let mut out = vec![DVec3::ZERO; store.len() as usize];
    let (mut ids, mut nrm) = (Vec::new(), Vec::new());
    for t in store.tiles() {
        store.read_indices(t.start, t.count, &mut ids)?;
        col.read_f32(t.start, t.count, &mut nrm)?;
        for (k, &id) in ids.iter().enumerate() {
            let n = &nrm[3 * k..3 * k + 3];
            out[id as usize] = DVec3::new(n[0] as f64, n[1] as f64, n[2] as f64);
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_flips_and_angles() {
        let truth = vec![DVec3::Z; 4];
        let n = vec![DVec3::Z, -DVec3::Z, DVec3::new(0.0, 1.0, 1.0), DVec3::ZERO];
        let a = accuracy(&n, &truth);
        assert_eq!(a.compared, 3);
        assert!((a.oriented_fraction - 2.0 / 3.0).abs() < 1e-12);
        assert!(a.median_angle_deg.abs() < 1e-9);
        assert!((a.p95_angle_deg - 45.0).abs() < 1e-9);
    }

    #[test]
    fn coincident_points_are_marked_and_can_be_left_out() {
        let p = [
            DVec3::X,
            DVec3::Y,
            DVec3::X,
            DVec3::Z,
            -DVec3::ZERO,
            DVec3::ZERO,
        ];
        // -0.0 and 0.0 differ in bits: not the same stored position.
        assert_eq!(coincident(&p), [true, false, true, false, false, false]);
        let truth = [DVec3::Z, DVec3::Z, -DVec3::Z, DVec3::Z, DVec3::Z, DVec3::Z];
        let n = [DVec3::Z; 6];
        let keep: Vec<bool> = coincident(&p).iter().map(|c| !c).collect();
        assert!((accuracy(&n, &truth).oriented_fraction - 5.0 / 6.0).abs() < 1e-12);
        assert_eq!(accuracy_where(&n, &truth, &keep).oriented_fraction, 1.0);
    }
}
