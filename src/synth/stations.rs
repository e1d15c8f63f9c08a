//! An object scanned from several stations, as a terrestrial scanner sees
//! it: stations in a ring around and above the object, each scan holding
//! only what faces its station (back faces unseen), nothing below the
//! object's base (it stands on the ground), and each scan misregistered by
//! a rigid shift of its own (real registration leaves a few tenths of a
//! spacing), so the scans' overlaps do not agree exactly.
//!
//! Visibility is by facing alone: a part hidden behind another part that
//! faces the station is still seen (no ray casting), which only makes the
//! scans more complete than a real scanner's; the base, the back faces and
//! the misregistration are what the reconstruction must live with.

use super::{stream, Rng, Scan, Shape, SynthError};
use glam::DVec3;

/// How the object is scanned.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stations {
    /// Scans, in a ring around the object's centre.
    pub count: usize,
    /// Distance of each station from the centre, horizontally.
    pub distance: f64,
    /// Height of the stations above the centre.
    pub height: f64,
    /// Height above the lowest point of the object below which nothing
    /// is scanned (the base it stands on).
    pub base: f64,
    /// Shift of each scan, drawn uniformly between these lengths in a
    /// random direction.
    pub misregistration: (f64, f64),
}

/// Least cosine between a surface normal and the direction to the station
/// for the point to be seen: the scanner misses grazing surfaces.
const GRAZING: f64 = 0.15;

/// `n` samples of `shape` per scan (noise `noise`), each kept when its
/// scan's station sees it; the points of all scans, misregistered, and for
/// each its scan's index. `centre` and `lowest` place the stations.
pub fn scan_from_stations(
    shape: &Shape,
    n: usize,
    noise: f64,
    stations: &Stations,
    (centre, lowest): (DVec3, f64),
    seed: u64,
) -> Result<(Scan, Vec<usize>), SynthError> {
    let mut rng = Rng::new(seed ^ 0x5ca7_7e12);
    let (mut scan, mut owner) = (Scan::default(), Vec::new());
    for k in 0..stations.count {
        let angle = k as f64 * std::f64::consts::TAU / stations.count as f64;
        let station = centre
            + DVec3::new(
                stations.distance * angle.cos(),
                stations.distance * angle.sin(),
                stations.height,
            );
        let (lo, hi) = stations.misregistration;
        let shift = rng.unit_vector() * rng.range(lo, hi);
        let mut one = Scan::default();
        stream(shape, n, noise, seed.wrapping_add(k as u64 + 1))?.fill(
            n,
            &mut one.points,
            &mut one.normals,
        );
        for (p, normal) in one.points.iter().zip(&one.normals) {
            let to_station = (station - *p).normalize_or_zero();
            if normal.dot(to_station) < GRAZING || p.z < lowest + stations.base {
                continue;
            }
            scan.points.push(*p + shift);
            scan.normals.push(*normal);
            owner.push(k);
        }
    }
    Ok((scan, owner))
}
