//! Which cubes of the band the zero set crosses, found by following the
//! surface from the cubes that hold samples (continuation: Wyvill,
//! McPheeters and Wyvill 1986; Bloomenthal 1988), so the field is evaluated
//! next to the surface only, not throughout the band (issue 43).
//!
//! Deviation from paper 1 section 2.6, which marches every cube of the
//! bounding box (and from this kernel's earlier band, every cube within
//! [`super::kernel::ImplicitKernel::band`] cubes of a sample): the 1M noisy
//! dragon's band held 7.8 million cubes for 1.2 million the surface
//! crosses, and the corners of the other 85 % cost most of a run. Here
//! the cubes that hold a sample are evaluated first; a cube the surface
//! crosses (every corner defined, one on the data, a sign change) passes the
//! walk to each face neighbour across a face whose corners change sign, as
//! long as that neighbour lies in the band. What is dropped: a piece of the
//! zero set farther than [`FOLLOW_STEPS`] such steps from every crossed cube
//! holding a sample (a sheet the field makes between samples but no sample
//! lies on, which the data does not support).
//!
//! Tiled == untiled: a cube's distance in steps from the seeds, up to
//! [`FOLLOW_STEPS`], depends only on cubes within that many cubes of it, so
//! a tile that walks the cubes within [`FOLLOW_STEPS`] of its core, seeded
//! by every sample-holding cube there, finds its own cubes' distances
//! exactly as a walk over the whole lattice does.

use super::cubes::{
    corner_key, corner_of, cube_range, inside, occupied, owns, CornerCursor, CUBES_PER_TASK,
};
use super::dilate::dilate;
use super::lattice::{in_key_range, Lattice};
use super::refine::CornerValue;
use super::sdf::Known;
use crate::geom::Aabb;
use crate::pipeline::KernelError;
use glam::DVec3;
use rayon::prelude::*;

/// Steps (face crossings) the walk takes from a crossed cube holding a
/// sample. Twice the default band (3 cubes): a crossed band cube lies
/// within the band's Chebyshev reach of a sample, which a walk of face
/// steps along an oblique surface covers in up to twice as many. Measured
/// against the band's own triangles: at 6 steps the 1M noisy dragon keeps
/// all but 161 (5 pieces, 1.9 to 10 spacings from every sample), the
/// terrain, the torus, the hole plane and four real scans all; at 9 the
/// dragon keeps 110 more (7 spacings from the samples, flaps off the
/// data) and the density step's sparse side 129 more, for 5 % more time.
pub const FOLLOW_STEPS: i64 = 6;

/// The cubes a walk over the lattice may visit and how they are judged.
pub(crate) struct Walk<'a> {
    pub lattice: &'a Lattice,
    /// The tile's core: the cubes it owns and keeps.
    pub core: &'a Aabb,
    /// Band half-width in cubes: a cube is visited only within this many
    /// cubes (Chebyshev) of a sample's cube.
    pub band: i64,
    pub steps: i64,
}

/// The followed surface: the owned cubes it crosses (sorted) and the value
/// of every corner evaluated (sorted by key), with how many cubes the walk
/// visited.
pub(crate) struct Followed {
    pub cubes: Vec<[i64; 3]>,
    pub corners: Vec<CornerValue>,
    pub visited: usize,
}

impl Walk<'_> {
    /// Follows the zero set from the cubes holding `points`; `evaluate`
    /// gives the values at sorted, distinct corner keys. Every set is a
    /// sorted vector of keys (which order like `(x, y, z)`), so each step
    /// of the walk is a merge or a forward scan, not a hash lookup per
    /// corner.
    pub(crate) fn follow<E>(&self, points: &[DVec3], evaluate: E) -> Result<Followed, KernelError>
    where
        E: Fn(&[u64]) -> Result<Vec<Option<Known>>, KernelError>,
    {
        let region = self.region();
        let holds = occupied(self.lattice, points)?;
        let mut frontier: Vec<u64> = holds
            .iter()
            .copied()
            .filter(|&k| inside(&region, corner_of(k)))
            .collect();
        let mut seen = holds.clone();
        let mut values: Vec<CornerValue> = Vec::new();
        let (mut kept, mut visited) = (Vec::new(), 0);
        for depth in 0..=self.steps {
            visited += frontier.len();
            let corners = dilate(&frontier, 0..=1).map_err(KernelError::failed)?;
            let need = difference(&corners, &values, |e| e.0);
            let got = evaluate(&need)?;
            let new: Vec<CornerValue> = need.into_iter().zip(got).collect();
            merge_into(&mut values, &new, |e| e.0);
            let last = depth == self.steps;
            let steps: Vec<Vec<Step>> = frontier
                .par_chunks(CUBES_PER_TASK)
                .map(|chunk| self.steps_of(&values, &region, chunk, last))
                .collect::<Result<_, _>>()?;
            let mut next: Vec<u64> = Vec::new();
            for step in steps.into_iter().flatten() {
                kept.extend(step.kept);
                next.extend(step.onward.iter().flatten());
            }
            next.par_sort_unstable();
            next.dedup();
            let next = difference(&next, &seen, |&k| k);
            merge_into(&mut seen, &next, |&k| k);
            let near: Vec<bool> = next
                .par_iter()
                .map(|&k| self.in_band(&holds, corner_of(k)))
                .collect::<Result<_, _>>()?;
            frontier = next
                .into_iter()
                .zip(near)
                .filter_map(|(k, near)| near.then_some(k))
                .collect();
        }
        kept.par_sort_unstable();
        Ok(Followed {
            cubes: kept.into_iter().map(corner_of).collect(),
            corners: values,
            visited,
        })
    }

    /// What the sorted frontier cubes of `chunk` give: each itself if the
    /// surface crosses it and the tile owns it, and (unless `last`) the
    /// neighbours across its faces whose corners change sign, within the
    /// region.
    fn steps_of(
        &self,
        values: &[CornerValue],
        region: &[[i64; 2]; 3],
        chunk: &[u64],
        last: bool,
    ) -> Result<Vec<Step>, KernelError> {
        let Some(&first) = chunk.first() else {
            return Ok(Vec::new());
        };
        let mut cursor = CornerCursor::new(values, corner_of(first), false)?;
        let mut steps = Vec::new();
        for &key in chunk {
            let cube = corner_of(key);
            let Some((v, _)) = cursor.values(cube)? else {
                continue;
            };
            if !changes_sign(v) {
                continue;
            }
            let mut step = Step {
                kept: owns(self.lattice, self.core, cube).then_some(key),
                onward: [None; 6],
            };
            if !last {
                for ((offset, face), onward) in FACES.iter().zip(step.onward.iter_mut()) {
                    let n = std::array::from_fn(|a| cube[a] + offset[a]);
                    if changes_sign(face.map(|c| v[c])) && inside(region, n) && in_key_range(n) {
                        *onward = Some(corner_key(n).map_err(KernelError::failed)?);
                    }
                }
            }
            steps.push(step);
        }
        Ok(steps)
    }

    /// The cubes within `steps` of an owned one (and a few more).
    fn region(&self) -> [[i64; 2]; 3] {
        cube_range(self.lattice, self.core, self.steps)
    }

    /// Whether a cube holding a sample (`holds`, sorted) lies within the
    /// band of `cube`, nearest cubes asked first (most answers come from
    /// the first ring).
    fn in_band(&self, holds: &[u64], cube: [i64; 3]) -> Result<bool, KernelError> {
        for r in 0..=self.band {
            for d in shell(r) {
                let c = std::array::from_fn(|a| cube[a] + d[a]);
                if in_key_range(c)
                    && holds
                        .binary_search(&corner_key(c).map_err(KernelError::failed)?)
                        .is_ok()
                {
                    return Ok(true);
                }
            }
        }
        Ok(false)
    }
}

/// One crossed frontier cube's part in the walk (see [`Walk::steps_of`]).
struct Step {
    kept: Option<u64>,
    onward: [Option<u64>; 6],
}

/// The keys of sorted `keys` not in `set`, sorted by `key_of`.
fn difference<T>(keys: &[u64], set: &[T], key_of: impl Fn(&T) -> u64) -> Vec<u64> {
    let mut at = 0;
    keys.iter()
        .copied()
        .filter(|&k| {
            at += set[at..].partition_point(|e| key_of(e) < k);
            set.get(at).is_none_or(|e| key_of(e) != k)
        })
        .collect()
}

/// Merges `b` into `a`, both sorted by `key_of` with no key in both, in
/// place from the back: the walk's corner values grow by a frontier's at
/// each step, and a new vector per step was most of its allocations.
fn merge_into<T: Copy>(a: &mut Vec<T>, b: &[T], key_of: impl Fn(&T) -> u64) {
    let (mut i, mut j) = (a.len(), b.len());
    let Some(&fill) = b.first() else {
        return;
    };
    a.resize(i + j, fill);
    while j > 0 {
        let to = i + j - 1;
        if i > 0 && key_of(&a[i - 1]) > key_of(&b[j - 1]) {
            a[to] = a[i - 1];
            i -= 1;
        } else {
            a[to] = b[j - 1];
            j -= 1;
        }
    }
}

/// Offsets at Chebyshev distance exactly `r`.
fn shell(r: i64) -> impl Iterator<Item = [i64; 3]> {
    let span = move || -r..=r;
    span()
        .flat_map(move |x| span().flat_map(move |y| span().map(move |z| [x, y, z])))
        .filter(move |d| d.iter().map(|v| v.abs()).max() == Some(r))
}

fn changes_sign<const N: usize>(values: [f64; N]) -> bool {
    let positive = values.iter().filter(|v| **v > 0.0).count();
    positive > 0 && positive < N
}

/// The six face neighbours' offsets and the corners (in `CORNERS`
/// order: bit 0 x, bit 1 y, bit 2 z) of the face each lies across.
const FACES: [([i64; 3], [usize; 4]); 6] = [
    ([-1, 0, 0], [0, 2, 4, 6]),
    ([1, 0, 0], [1, 3, 5, 7]),
    ([0, -1, 0], [0, 1, 4, 5]),
    ([0, 1, 0], [2, 3, 6, 7]),
    ([0, 0, -1], [0, 1, 2, 3]),
    ([0, 0, 1], [4, 5, 6, 7]),
];

#[cfg(test)]
mod tests {
    use super::*;
    use crate::recon::implicit::cubes::CORNERS;

    #[test]
    fn faces_name_the_corners_on_their_side() {
        for (offset, face) in FACES {
            let axis = offset.iter().position(|&o| o != 0).expect("axis");
            let side = i64::from(offset[axis] > 0);
            for c in face {
                assert_eq!(CORNERS[c][axis], side, "{offset:?} {c}");
            }
        }
    }

    #[test]
    fn merging_in_place_is_the_sorted_union() {
        let mut rng = crate::rng::Rng::new(7);
        for _ in 0..50 {
            let mut all: Vec<u64> = (0..rng.below(40)).map(|_| rng.below(1000)).collect();
            all.sort_unstable();
            all.dedup();
            let (mut a, mut b) = (Vec::new(), Vec::new());
            for &k in &all {
                if rng.below(2) == 0 {
                    a.push(k);
                } else {
                    b.push(k);
                }
            }
            merge_into(&mut a, &b, |&k| k);
            assert_eq!(a, all);
        }
    }

    #[test]
    fn shells_partition_the_block() {
        let mut all: Vec<[i64; 3]> = (0..=2).flat_map(shell).collect();
        assert_eq!(all.len(), 125);
        all.sort_unstable();
        all.dedup();
        assert_eq!(all.len(), 125);
        assert_eq!(shell(0).count(), 1);
        assert_eq!(shell(1).count(), 26);
    }

    /// Samples of the unit sphere (a Fibonacci spiral), about 0.05 apart.
    fn sphere_samples() -> Vec<DVec3> {
        let n = 5000;
        let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
        (0..n)
            .map(|i| {
                let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
                let r = (1.0 - z * z).sqrt();
                let a = golden * i as f64;
                DVec3::new(r * a.cos(), r * a.sin(), z)
            })
            .collect()
    }

    /// A field whose zero set is the unit sphere and, when `phantom`, a
    /// second sphere of radius 1.2 no sample lies on (within the band).
    fn field(
        lattice: &Lattice,
        phantom: bool,
    ) -> impl Fn(&[u64]) -> Result<Vec<Option<Known>>, KernelError> + '_ {
        move |keys: &[u64]| {
            Ok(keys
                .iter()
                .map(|&k| {
                    let r = lattice.corner(corner_of(k)).length();
                    let f = if phantom {
                        (r - 1.0) * (1.2 - r)
                    } else {
                        r - 1.0
                    };
                    Some(Known::OnData(f, Default::default()))
                })
                .collect())
        }
    }

    /// Every owned cube of the whole band that marching cubes draws: what
    /// the kernel marched before the walk.
    fn band_reference(walk: &Walk, points: &[DVec3], phantom: bool) -> Vec<[i64; 3]> {
        let holds = occupied(walk.lattice, points).expect("occupied");
        let band = dilate(&holds, -walk.band..=walk.band).expect("band");
        let corners = dilate(&band, 0..=1).expect("corners");
        let values = field(walk.lattice, phantom)(&corners).expect("values");
        let values: Vec<CornerValue> = corners.into_iter().zip(values).collect();
        let mut cursor = CornerCursor::new(&values, corner_of(band[0]), false).expect("cursor");
        band.iter()
            .map(|&k| corner_of(k))
            .filter(|&c| owns(walk.lattice, walk.core, c))
            .filter(|&c| {
                let v = cursor.values(c).expect("values");
                v.is_some_and(|(v, _)| changes_sign(v))
            })
            .collect()
    }

    #[test]
    fn the_walk_finds_every_crossed_cube_of_the_band_on_the_data() {
        let points = sphere_samples();
        let lattice = Lattice::new(DVec3::splat(0.013), 0.07).expect("lattice");
        let everywhere = Aabb::new(DVec3::NEG_INFINITY, DVec3::INFINITY);
        let walk = Walk {
            lattice: &lattice,
            core: &everywhere,
            band: 3,
            steps: FOLLOW_STEPS,
        };
        let followed = walk.follow(&points, field(&lattice, false)).expect("walk");
        let reference = band_reference(&walk, &points, false);
        assert!(reference.len() > 2000, "{}", reference.len());
        assert_eq!(followed.cubes, reference);
        // It evaluated the corners near the surface, not the band's.
        assert!(
            followed.visited < 2 * reference.len(),
            "{}",
            followed.visited
        );
    }

    #[test]
    fn a_sheet_no_sample_lies_on_is_dropped_and_tiles_agree() {
        let points = sphere_samples();
        let lattice = Lattice::new(DVec3::splat(0.013), 0.07).expect("lattice");
        let everywhere = Aabb::new(DVec3::NEG_INFINITY, DVec3::INFINITY);
        let walk = |core| Walk {
            lattice: &lattice,
            core,
            band: 3,
            steps: FOLLOW_STEPS,
        };
        let whole = walk(&everywhere);
        let followed = whole.follow(&points, field(&lattice, true)).expect("walk");
        let on_data = band_reference(&whole, &points, false);
        let with_phantom = band_reference(&whole, &points, true);
        // The band holds the sheet at radius 1.2; the walk keeps the sphere.
        assert!(with_phantom.len() > on_data.len() + 1000);
        assert_eq!(followed.cubes, on_data);
        // Two halves of space as tiles: together, exactly the whole walk.
        let cut = 0.3;
        let halves = [
            Aabb::new(
                DVec3::NEG_INFINITY,
                DVec3::new(cut, f64::INFINITY, f64::INFINITY),
            ),
            Aabb::new(
                DVec3::new(cut, f64::NEG_INFINITY, f64::NEG_INFINITY),
                DVec3::INFINITY,
            ),
        ];
        let mut joined: Vec<[i64; 3]> = halves
            .iter()
            .flat_map(|core| {
                walk(core)
                    .follow(&points, field(&lattice, true))
                    .expect("walk")
                    .cubes
            })
            .collect();
        joined.sort_unstable();
        let mut whole_cubes = followed.cubes.clone();
        whole_cubes.sort_unstable();
        assert_eq!(joined, whole_cubes);
    }
}
