//! The propagation sources (paper 5 step 2, items 1-2): the points of largest
//! and smallest x, y and z, whose normals are set along +-X, +-Y, +-Z, or for
//! a single-sheet model the one point farthest along a chosen direction.
//!
//! Ties go to the smaller input id, and a point that is extreme on two axes
//! is a source once (the paper's "exclude coincident sources"), for its first
//! direction in the paper's stack order CSX, CSX-, CSY, CSY-, CSZ, CSZ-.

use glam::DVec3;

/// Where the propagation starts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Sources {
    /// The six extreme points along +-X, +-Y, +-Z (closed models).
    Six,
    /// The point farthest along this direction, its normal along it
    /// (single-sheet models: terrain with +Z).
    Single(DVec3),
}

impl Sources {
    /// Source directions in stack order (unit; a zero or non-finite single
    /// direction gives none).
    pub fn directions(&self) -> Vec<DVec3> {
        match *self {
            Sources::Six => vec![
                DVec3::X,
                -DVec3::X,
                DVec3::Y,
                -DVec3::Y,
                DVec3::Z,
                -DVec3::Z,
            ],
            Sources::Single(d) => d.try_normalize().into_iter().collect(),
        }
    }
}

/// One chosen source: the point (by id and by its index in the caller's
/// slice or stream) and the direction its normal must face.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Extreme {
    /// Input-order id of the extreme point.
    pub id: u64,
    /// Its index in the caller's slice or stream.
    pub index: u64,
    /// The direction its normal must face.
    pub direction: DVec3,
}

/// Streaming selection of the extreme points along each direction, so the
/// whole store can be scanned tile by tile.
#[derive(Clone, Debug)]
pub struct Extremes {
    dirs: Vec<DVec3>,
    /// Per direction: (projection, id, index) of the best point so far.
    best: Vec<Option<(f64, u64, u64)>>,
}

impl Extremes {
    /// An empty selection of the extremes along each direction of `sources`.
    pub fn new(sources: &Sources) -> Self {
        let dirs = sources.directions();
        let best = vec![None; dirs.len()];
        Extremes { dirs, best }
    }

    /// Considers a point (only points with a normal should be offered).
    pub fn offer(&mut self, p: DVec3, id: u64, index: u64) {
        for (d, best) in self.dirs.iter().zip(&mut self.best) {
            let s = p.dot(*d);
            let better = match best {
                None => true,
                Some((bs, bid, _)) => s > *bs || (s == *bs && id < *bid),
            };
            if better {
                *best = Some((s, id, index));
            }
        }
    }

    /// The sources in stack order, each point once.
    pub fn finish(&self) -> Vec<Extreme> {
        let mut out: Vec<Extreme> = Vec::with_capacity(self.dirs.len());
        for (d, best) in self.dirs.iter().zip(&self.best) {
            if let Some((_, id, index)) = *best {
                if out.iter().all(|e| e.id != id) {
                    out.push(Extreme {
                        id,
                        index,
                        direction: *d,
                    });
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn picks_extremes_with_id_ties_and_no_duplicates() {
        let pts = [
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(1.0, 5.0, 0.0),
            DVec3::new(-2.0, -1.0, 3.0),
            DVec3::new(0.0, 0.0, -4.0),
        ];
        let ids = [9u64, 3, 5, 7];
        let mut ex = Extremes::new(&Sources::Six);
        for (i, p) in pts.iter().enumerate() {
            ex.offer(*p, ids[i], i as u64);
        }
        let got: Vec<(u64, DVec3)> = ex.finish().iter().map(|e| (e.id, e.direction)).collect();
        // +x ties between ids 9 and 3 -> 3, which is also +y; id 5 is -x,
        // -y and +z: each kept once, for its first direction.
        assert_eq!(got, vec![(3, DVec3::X), (5, -DVec3::X), (7, -DVec3::Z)]);
    }

    #[test]
    fn single_direction_is_normalised() {
        let d = Sources::Single(DVec3::new(0.0, 0.0, 2.0)).directions();
        assert_eq!(d, vec![DVec3::Z]);
        assert!(Sources::Single(DVec3::ZERO).directions().is_empty());
    }
}
