//! What the scan itself knows about which way its normals face, and the
//! check of a run's normals against it (issue 38).
//!
//! - A terrestrial scan's stations: an E57 file gives each scan's pose,
//!   whose translation is where the scanner stood (ASTM E2807), and a
//!   scanner sees a surface only from its own side, so a normal faces its
//!   own scan's station (`PITFALLS.md`: "Single-station scans: orient
//!   toward the scanner position"; here per scan, for any number of them).
//! - Aerial lidar: no station in the file, but the sensor looks down
//!   (beams within some 30 degrees of nadir), so every surface it sees
//!   faces up unless it turns past vertical.
//!
//! [`Orientation::Auto`], the default, resolves to the orientation the
//! evidence asks for ([`resolve`]); `check` counts, after any
//! orientation, the normals that disagree with the evidence, so a summary
//! that says "0 unoriented" also says how many face the wrong way.

use super::{NormalsError, Orientation, FLAG_DEGENERATE};
use crate::store::{Column, Coordinates, PointStore, Station};
use glam::DVec3;
use rayon::prelude::*;

/// What a scan was taken with, as a hint to [`Orientation::Auto`].
#[derive(
    Clone,
    Copy,
    Debug,
    PartialEq,
    Eq,
    Default,
    serde::Serialize,
    serde::Deserialize,
    clap::ValueEnum,
)]
pub enum Sensor {
    /// Judge from the data (see [`resolve`]).
    #[default]
    #[value(help = "Judge from the data")]
    Auto,
    /// Airborne lidar: normals face up, the tree repairs the rest.
    #[value(help = "Airborne lidar")]
    Aerial,
    /// Ground-based or an object: toward the stations the input gives,
    /// else the spanning tree (never "up").
    #[value(help = "Ground-based scanner, or an object")]
    Terrestrial,
}

/// Least ratio of horizontal to vertical extent at which a LAS or LAZ input
/// without stations is taken for aerial. LAS is the airborne survey's
/// format; a terrestrial LAS of a tower or a single tree is taller than
/// wide. Measured: a town (autzen) 10:1, forest and urban tiles of
/// 2-4:1, a stand of trees (lone-star) 2.6:1.
pub const AERIAL_LAS_RATIO: f64 = 1.0;

/// The same for inputs of other formats, along both horizontal axes,
/// where a closed object (a torus is 4.3:1, its underside faces down) must
/// not be taken for terrain: only a sheet "much wider than tall".
pub const AERIAL_OTHER_RATIO: f64 = 10.0;

/// Least `|n.z|` of a normal the aerial check counts: a surface within 60
/// degrees of horizontal, which an airborne sensor sees from above.
pub const NEAR_HORIZONTAL: f64 = 0.5;

/// The evidence a store carries.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Evidence {
    /// Each point's own scan station.
    Stations,
    /// Up, for near-horizontal surfaces (aerial).
    Up,
}

impl Evidence {
    /// The evidence of `store` under the hint `sensor`, if any.
    pub fn of(store: &PointStore, sensor: Sensor) -> Option<Evidence> {
        let stations = !store.manifest().stations.is_empty();
        match sensor {
            Sensor::Aerial => Some(Evidence::Up),
            Sensor::Terrestrial => stations.then_some(Evidence::Stations),
            Sensor::Auto if stations => Some(Evidence::Stations),
            Sensor::Auto => looks_aerial(store).then_some(Evidence::Up),
        }
    }

    /// What the summary calls it.
    pub fn describe(self) -> &'static str {
        match self {
            Evidence::Stations => "facing away from their scan's station",
            Evidence::Up => "near-horizontal and facing down (aerial)",
        }
    }
}

/// Whether a store without stations looks like aerial data: a LAS input
/// (its coordinates kept as the file's integers) whose wider horizontal
/// extent is at least [`AERIAL_LAS_RATIO`] times its height; any other
/// input whose both horizontal extents are [`AERIAL_OTHER_RATIO`] times its
/// height (a sheet spread both ways: a sphere with one stray point 50
/// radii to its side is 25 times wider than tall along x, not along y).
/// The LAS header's global encoding says nothing of the platform (GPS time
/// type, waveform, synthetic returns, WKT), so it is not used.
pub fn looks_aerial(store: &PointStore) -> bool {
    let m = store.manifest();
    let ext = |a: usize| m.bounds_max[a] - m.bounds_min[a];
    let tall = ext(2);
    match m.coordinates {
        Coordinates::LasGrid { .. } => {
            let wide = ext(0).max(ext(1));
            wide > 0.0 && wide >= AERIAL_LAS_RATIO * tall
        }
        Coordinates::F64 => {
            let narrow = ext(0).min(ext(1));
            narrow > 0.0 && narrow >= AERIAL_OTHER_RATIO * tall
        }
    }
}

/// The orientation `orientation` asks for on `store`: [`Orientation::Auto`]
/// turns into [`Orientation::Stations`] (the store has stations),
/// [`Orientation::Aerial`] (aerial evidence) or the spanning tree; asking
/// for stations of a store without any is an error.
pub fn resolve(orientation: Orientation, store: &PointStore) -> Result<Orientation, NormalsError> {
    match orientation {
        Orientation::Auto(sensor) => Ok(match Evidence::of(store, sensor) {
            Some(Evidence::Stations) => Orientation::Stations,
            Some(Evidence::Up) => Orientation::Aerial,
            None => Orientation::SpanningTree,
        }),
        Orientation::Stations if store.manifest().stations.is_empty() => Err(
            NormalsError::BadParameter(super::BadNormalParameter::NoStations),
        ),
        o => Ok(o),
    }
}

/// The stations of a store relative to its origin, for per-point lookups.
#[derive(Clone, Debug, Default)]
pub(crate) struct StationTable {
    /// Sorted by first input index.
    runs: Vec<(u64, u64, DVec3)>,
}

impl StationTable {
    /// `stations` with positions made relative to `origin`.
    pub(crate) fn new(stations: &[Station], origin: DVec3) -> Self {
        let mut runs: Vec<(u64, u64, DVec3)> = stations
            .iter()
            .map(|s| (s.first, s.end, DVec3::from_array(s.position) - origin))
            .collect();
        runs.sort_by_key(|r| r.0);
        StationTable { runs }
    }

    /// The station (relative to the origin) of the point with input index
    /// `id`, if a run holds it.
    pub(crate) fn of(&self, id: u64) -> Option<DVec3> {
        let at = self.runs.partition_point(|r| r.0 <= id).checked_sub(1)?;
        let (_, end, p) = self.runs[at];
        (id < end).then_some(p)
    }
}

/// How a run's normals stand against the scan's evidence.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct EvidenceCheck {
    /// The evidence checked against.
    pub evidence: Evidence,
    /// Normals the evidence speaks for: with stations, every normal of a
    /// point with a station; aerial, every normal within 60 degrees of
    /// vertical.
    pub checked: u64,
    /// Of those, the normals that face the other way.
    pub against: u64,
}

/// Counts the normals of `store` (columns `normals`, `flags`) that
/// disagree with `evidence`.
pub(crate) fn check(
    store: &PointStore,
    evidence: Evidence,
    normals: &Column,
    flags: &Column,
) -> Result<EvidenceCheck, NormalsError> {
    let table = StationTable::new(&store.manifest().stations, store.origin());
    let counts: Vec<(u64, u64)> = store
        .tiles()
        .par_iter()
        .map(|t| {
            let (mut xyz, mut ids, mut nrm, mut flg) =
                (Vec::new(), Vec::new(), Vec::new(), Vec::new());
            store.read_coords(t.start, t.count, &mut xyz)?;
            store.read_indices(t.start, t.count, &mut ids)?;
            normals.read_f32(t.start, t.count, &mut nrm)?;
            flags.read_u8(t.start, t.count, &mut flg)?;
            let (mut checked, mut against) = (0, 0);
            for (i, &id) in ids.iter().enumerate() {
                if flg[i] & FLAG_DEGENERATE != 0 {
                    continue;
                }
                let n = super::normal_at(&nrm, i);
                let p = DVec3::new(
                    f64::from(xyz[3 * i]),
                    f64::from(xyz[3 * i + 1]),
                    f64::from(xyz[3 * i + 2]),
                );
                let wrong = match evidence {
                    Evidence::Stations => match table.of(id) {
                        Some(s) => n.dot(s - p) < 0.0,
                        None => continue,
                    },
                    Evidence::Up if n.z.abs() >= NEAR_HORIZONTAL => n.z < 0.0,
                    Evidence::Up => continue,
                };
                checked += 1;
                against += u64::from(wrong);
            }
            Ok((checked, against))
        })
        .collect::<Result<_, NormalsError>>()?;
    Ok(EvidenceCheck {
        evidence,
        checked: counts.iter().map(|c| c.0).sum(),
        against: counts.iter().map(|c| c.1).sum(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_point_finds_its_own_station_and_none_outside_the_runs() {
        let st = |first, end, x| Station {
            first,
            end,
            position: [x, 0.0, 0.0],
        };
        let t = StationTable::new(
            &[st(10, 20, 2.0), st(0, 10, 1.0), st(25, 30, 3.0)],
            DVec3::X,
        );
        assert_eq!(t.of(0), Some(DVec3::ZERO));
        assert_eq!(t.of(9), Some(DVec3::ZERO));
        assert_eq!(t.of(10), Some(DVec3::X));
        assert_eq!(t.of(19), Some(DVec3::X));
        assert_eq!(t.of(22), None);
        assert_eq!(t.of(29), Some(2.0 * DVec3::X));
        assert_eq!(t.of(30), None);
        assert_eq!(StationTable::default().of(0), None);
    }
}
