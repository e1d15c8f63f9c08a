//! The implicit-reconstruction tile kernel (paper 1 sections 2.5-2.6): the
//! signed distance at the corners of the lattice cubes near the samples,
//! marching cubes on the cubes whose corners are all defined and not all
//! beyond the data's edge ([`Known::Beyond`]). Open surfaces: the cubes the
//! zero set crosses, found by walking the surface from the cubes holding
//! samples ([`super::follow`]); with `--closed`, every cube of the band that
//! may change sign, every corner having a value ([`super::closed`]). A tile
//! owns the blocks of cubes whose min corner lies in its core box
//! (half-open), so every cube is polygonised by exactly one tile, and flat
//! blocks are then re-triangulated whole ([`super::blocks`]).
//!
//! Deviation: the paper marches the whole bounding box; here only cubes
//! within the band (a few spacings of a sample's cube) are asked. A surface
//! piece farther from every sample than that is not supported by the data,
//! and the band keeps the work proportional to the surface rather than the
//! volume.

use super::blocks::{merge_flat_blocks, BLOCK};
use super::closed::{self, Everywhere};
use super::cubes::{
    corner_of, cube_range, inside, occupied, owned_range, CornerCursor, CUBES_PER_TASK,
};
use super::dilate::dilated_count;
use super::field::Field;
use super::follow::{Walk, FOLLOW_STEPS};
use super::lattice::{edge_from_key, Lattice};
use super::polygonize::{polygonize_cube, CubeVertex};
use super::refine::{refine_vertices, CornerValue};
use super::sdf::{Corner, Fit, Known, Samples};
use crate::geom::Aabb;
use crate::normals::{FLAG_DEGENERATE, FLAG_UNORIENTED};
use crate::pipeline::{KernelError, TileKernel};
use crate::spatial::grid::GridIndex;
use crate::store::{ColumnSpec, FLAGS, NORMALS};
use crate::tiling::{MissingColumns, TilePoints};
use glam::DVec3;
use rayon::prelude::*;

/// What one tile contributes: its cubes' triangles, vertices keyed by
/// global lattice edge, in block order.
#[derive(Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct ImplicitTile {
    pub triangles: Vec<[CubeVertex; 3]>,
    /// Cubes whose corners the field was asked for: the walk's (open),
    /// the band's (`--closed`).
    pub cubes: usize,
    pub undefined_corners: usize,
    /// Triangles in cubes a corner of which the winding number decided.
    pub away: usize,
    /// Triangles fewer after flat blocks were re-triangulated.
    pub merged: usize,
}

impl ImplicitTile {
    /// Whether a saved result could be a tile's marching cubes: every
    /// vertex on a lattice edge its key names, at a finite place, three
    /// distinct vertices a triangle, counts that sum without overflow.
    pub(crate) fn fits(&self, _: &crate::store::TileEntry, _: u64) -> bool {
        let vertex = |v: &CubeVertex| edge_from_key(v.key).is_ok() && v.pos.is_finite();
        let triangle = |t: &[CubeVertex; 3]| {
            t.iter().all(vertex)
                && t[0].key != t[1].key
                && t[1].key != t[2].key
                && t[0].key != t[2].key
        };
        self.cubes < 1 << 48
            && self.undefined_corners < 1 << 48
            && self.merged < 1 << 48
            && self.away <= self.triangles.len() + self.merged
            && self.triangles.iter().all(triangle)
    }
}

pub struct ImplicitKernel {
    pub lattice: Lattice,
    /// `rho + delta`, infinite when the surface is known to be closed.
    pub limit: f64,
    pub initial_margin: f64,
    /// Cubes within this many cubes of a sample's cube form the band.
    pub band: i64,
    /// The signed distance, and with it how vertices are placed.
    pub field: Field,
    /// Mean nearest-neighbour distance of the samples (sizes the index).
    pub spacing: f64,
    /// Peak bytes a cube of the band costs ([`BYTES_PER_CUBE`], or
    /// [`BYTES_PER_CUBE_CLOSED`] for a closed surface).
    pub bytes_per_cube: u64,
    /// With `--closed`: the sign of every corner away from the samples.
    pub everywhere: Option<Everywhere>,
    /// How far a vertex left out of a flat block may lie from the new
    /// triangles, in the points' units (0: no block is re-triangulated).
    pub flat_tolerance: f64,
}

/// Edge of the signed distance's grid index, in lattice cubes. Its queries
/// are lattice corners, which lie up to two cubes from the nearest sample
/// (the band), so a grid sized for the k-th neighbour (~2 spacings, the
/// automatic size) widens ring after ring for them; cells of 1.5 cubes
/// settle most corners in the first 27 cells. callgrind, reconstruct from a
/// 200k-point store with normals, 1 thread: kd-tree 2.15 G instructions,
/// grid of 0.5 / 1 / 1.5 / 2 / 3 cubes 4.11 / 1.88 / 1.55 / 1.56 / 1.79 G;
/// the same mesh from all (exact nearest either way).
const SDF_GRID_CELLS: f64 = 1.5;

/// Edge of the MLS field's grid index, in spacings. Its 16-nearest queries
/// reach about 4.5 spacings on the surface and more from corners off it.
/// User time, 1M dragon, cell 5e-4 (3.7 spacings), normals stored, cells
/// of 1.5 / 2.5 / 4 / 6 / 8 / 12 spacings: 20.8 / 9.8 / 6.5 / 5.1 / 5.3 /
/// 5.8 s (shared machine).
const MLS_GRID_SPACINGS: f64 = 7.0;

/// Bytes a tile holds per loaded point (its samples, normals, ids, the
/// tile's columns and the field's index) and per cube of its band (the
/// band's keys, the corners' keys and values, the triangles, 96 bytes
/// each, and their concatenation). Measured on 519k points of a
/// terrestrial scan as one tile, one thread, at four cells: 213, 405, 625
/// MiB at 0.57, 1.80, 3.15 million cubes (165 B a cube), 123 MiB with none
/// (230 B a point). A closed surface's cubes cost more (its field has no
/// distance limit, so every corner of the band gets a value and its
/// vertices and holes are kept): the same scan `--closed` as one tile, 608
/// MiB at 1.21 million cubes (430 B a cube).
const BYTES_PER_LOADED_POINT: u64 = 230;
pub(crate) const BYTES_PER_CUBE: u64 = 165;
pub(crate) const BYTES_PER_CUBE_CLOSED: u64 = 430;

/// Band cubes per core point at a cell of 2.2 mean spacings (the 1M and
/// 200k noisy dragons: 7.8 and 7.7); a surface's band holds about
/// (spacing / cell)^3 as many at other cells (3 spacings: 2.9 measured).
const CUBES_PER_POINT_AT_2_2: f64 = 7.7;

/// Peak bytes per loaded point the plan sizes tiles by, for a cell of
/// `cell_spacings` mean spacings (a loaded point is 2/3 of a core point
/// with the plan's margin): 1,076 at the open default, 1,100 at `--closed`'s
/// 3. The plan sized tiles by 650 whatever the cell, measured at 3
/// spacings before the open default became 2.2; each tile's own need
/// ([`tile_bytes`], its band counted) is what holds `--mem` where density
/// varies.
pub(crate) fn planned_bytes_per_loaded_point(cell_spacings: f64, per_cube: u64) -> u64 {
    let cubes = CUBES_PER_POINT_AT_2_2 * (2.2 / cell_spacings.max(0.1)).powi(3) / 1.5;
    BYTES_PER_LOADED_POINT + (cubes * per_cube as f64) as u64
}

/// What a tile of `points` loaded points and `cubes` band cubes of
/// `per_cube` bytes holds.
pub(crate) fn tile_bytes(points: u64, cubes: u64, per_cube: u64) -> u64 {
    points
        .saturating_mul(BYTES_PER_LOADED_POINT)
        .saturating_add(cubes.saturating_mul(per_cube))
}

impl TileKernel for ImplicitKernel {
    type Output = ImplicitTile;

    fn name(&self) -> &'static str {
        crate::store::StageId::MARCHING_CUBES.name()
    }

    fn codec(&self) -> Option<crate::pipeline::Codec<Self::Output>> {
        Some(crate::pipeline::Codec::serde(ImplicitTile::fits))
    }

    /// The tile's points and its band's cubes (counted first, exactly): a
    /// sparse region has many cubes per point, so a count of points alone
    /// let a terrestrial scan's tiles overrun `--mem` (519k points of a
    /// geyser cone at 256 MiB peaked at 308 MiB).
    /// With `--closed` the cubes are the band widened by one (where the
    /// field meets the winding number).
    fn bytes_for(&self, tile: &TilePoints) -> Option<u64> {
        let reach = self.band + i64::from(self.everywhere.is_some());
        let cubes = band_size(&self.lattice, &tile.points, &tile.core, reach).ok()?;
        let n = tile.points.len() as u64;
        Some(tile_bytes(n, cubes, self.bytes_per_cube))
    }

    fn bytes_to_load(&self, points: u64) -> Option<u64> {
        Some(tile_bytes(points, 0, self.bytes_per_cube))
    }

    fn margin(&self) -> f64 {
        self.initial_margin
    }

    fn reads(&self) -> &[ColumnSpec] {
        &[NORMALS, FLAGS]
    }

    fn run(&self, tile: &TilePoints) -> Result<ImplicitTile, KernelError> {
        if tile.margin < self.band_reach() {
            return Err(KernelError::MarginTooSmall {
                needed: self.band_reach(),
            });
        }
        let (points, normals, ids) =
            usable_samples(tile, self.takes_islands()).map_err(KernelError::failed)?;
        let index =
            GridIndex::with_cell(&points, &ids, self.index_cell()).map_err(KernelError::failed)?;
        let samples = Samples {
            points: &points,
            normals: &normals,
            index: &index,
        };
        let (cubes, corners, visited) = match &self.everywhere {
            None => {
                let walk = Walk {
                    lattice: &self.lattice,
                    core: &tile.core,
                    band: self.band,
                    steps: FOLLOW_STEPS,
                };
                let followed =
                    walk.follow(&points, |keys| self.evaluate_corners(&samples, tile, keys))?;
                (followed.cubes, followed.corners, followed.visited)
            }
            Some(e) => {
                let (cubes, corners) = self.closed_cubes(e, &samples, tile)?;
                let visited = cubes.len();
                (cubes, corners, visited)
            }
        };
        let mut out = ImplicitTile {
            cubes: visited,
            undefined_corners: corners.iter().filter(|c| c.1.is_none()).count(),
            ..ImplicitTile::default()
        };
        let parts: Vec<(Vec<[CubeVertex; 3]>, usize)> = cubes
            .par_chunks(CUBES_PER_TASK)
            .map(|chunk| self.polygonize_cubes(chunk, &corners))
            .collect::<Result<_, _>>()?;
        out.away = parts.iter().map(|p| p.1).sum();
        out.triangles = parts.into_iter().flat_map(|p| p.0).collect();
        if self.field == Field::Mls {
            refine_vertices(&self.lattice, &corners, &mut out.triangles)?;
        }
        if self.flat_tolerance > 0.0 {
            let before = out.triangles.len();
            out.triangles =
                merge_flat_blocks(std::mem::take(&mut out.triangles), self.flat_tolerance)?;
            out.merged = before - out.triangles.len();
        }
        Ok(out)
    }
}

impl ImplicitKernel {
    /// How far beyond the core the samples are needed. Open: the walk's
    /// distances count for cubes within [`FOLLOW_STEPS`] of an owned one,
    /// each of which asks whether a sample cube lies within the band of
    /// it: every sample within band + steps + 1 cubes (the field's own
    /// neighbours beyond that ask for more margin). With `--closed`, a coarse
    /// corner up to [`closed::COARSE`] cubes beyond the core is asked
    /// whether it is near the samples.
    fn band_reach(&self) -> f64 {
        // An owned block reaches BLOCK - 1 cubes past the core.
        let cubes = match self.everywhere {
            None => self.band + 1 + FOLLOW_STEPS,
            Some(_) => self.band + closed::COARSE + 3,
        } + BLOCK
            - 1;
        cubes as f64 * self.lattice.cell * 1.001
    }

    /// Whether islands take part: samples flagged unoriented because the
    /// paper's island rule left their component apart, signed by its own
    /// highest points (`normals::orient::Sign::Island`). The MLS field takes
    /// them; paper 1's own field leaves them out, as the paper does.
    ///
    /// Why: the rule leaves out components under a thousandth of the
    /// points, so the larger the scan, the larger the parts it drops (the
    /// 1M dragon's 102-point filament, whose loss set every Hausdorff
    /// distance: open 33.4 -> 11.3 spacings, `--closed` 33.4 -> 20.3). With
    /// `--closed`, a stray island closes into a small piece the piece
    /// filter drops.
    pub(crate) fn takes_islands(&self) -> bool {
        self.field == Field::Mls
    }

    /// Edge of the signed distance's grid index: [`SDF_GRID_CELLS`] cubes
    /// for paper 1's nearest-plane queries, [`MLS_GRID_SPACINGS`] spacings
    /// for the MLS field's [`super::mls::MLS_NEIGHBOURS`]-nearest ones
    /// (whose reach follows the spacing, not the cube).
    fn index_cell(&self) -> f64 {
        match self.field {
            Field::Paper1 => SDF_GRID_CELLS * self.lattice.cell,
            Field::Mls if self.spacing > 0.0 => MLS_GRID_SPACINGS * self.spacing,
            Field::Mls => self.lattice.cell,
        }
    }

    /// Marching cubes over sorted `cubes` (a run of the tile's), in order,
    /// and how many of the triangles lie in cubes a corner of which the
    /// winding number decided (`--closed`: the surface away from the data).
    fn polygonize_cubes(
        &self,
        cubes: &[[i64; 3]],
        corners: &[CornerValue],
    ) -> Result<(Vec<[CubeVertex; 3]>, usize), KernelError> {
        let (mut triangles, mut away) = (Vec::new(), 0);
        let Some(&first) = cubes.first() else {
            return Ok((triangles, away));
        };
        let mut cursor = CornerCursor::new(corners, first, self.everywhere.is_some())?;
        for cube in cubes {
            if let Some((values, winding)) = cursor.values(*cube)? {
                let before = triangles.len();
                polygonize_cube(&self.lattice, *cube, &values, &mut triangles)
                    .map_err(KernelError::failed)?;
                if winding {
                    away += triangles.len() - before;
                }
            }
        }
        Ok((triangles, away))
    }

    /// Signed distance at sorted, distinct corner `keys`.
    fn evaluate_corners(
        &self,
        samples: &Samples,
        tile: &TilePoints,
        keys: &[u64],
    ) -> Result<Vec<Option<Known>>, KernelError> {
        let evaluated: Vec<(Corner, Fit)> = keys
            .par_iter()
            .map_init(Vec::new, |nbr, &key| {
                let p = self.lattice.corner(corner_of(key));
                self.field.corner(samples, tile, p, self.limit, nbr)
            })
            .collect();
        let short = evaluated.iter().fold(0.0f64, |m, c| match c.0 {
            Corner::Short(s) => m.max(s),
            Corner::Value(_) | Corner::Beyond(_) => m,
        });
        KernelError::unless_short(short, tile.margin)?;
        Ok(evaluated
            .into_iter()
            .map(|(corner, fit)| corner.known(fit).unwrap_or(None))
            .collect())
    }
}

/// Loaded points whose normal is usable: not degenerate, and oriented or
/// (with `islands`) signed within an island.
type Usable = (Vec<DVec3>, Vec<DVec3>, Vec<u64>);

fn usable_samples(tile: &TilePoints, islands: bool) -> Result<Usable, MissingColumns> {
    let (normals, flags) = tile.oriented()?;
    let unusable = match islands {
        true => FLAG_DEGENERATE,
        false => FLAG_DEGENERATE | FLAG_UNORIENTED,
    };
    let keep = |i: &usize| flags[*i] & unusable == 0 && normals[*i] != DVec3::ZERO;
    let idx: Vec<usize> = (0..tile.points.len()).filter(keep).collect();
    Ok((
        idx.iter().map(|&i| tile.points[i]).collect(),
        idx.iter().map(|&i| normals[i]).collect(),
        idx.iter().map(|&i| tile.ids[i]).collect(),
    ))
}

/// How many owned cubes lie within `reach` cubes of a sample's cube.
fn band_size(
    lattice: &Lattice,
    points: &[DVec3],
    core: &Aabb,
    reach: i64,
) -> Result<u64, KernelError> {
    // Only sample cubes within reach of the core count (the margin holds
    // more, for the walk's steps).
    let range = cube_range(lattice, core, reach);
    let mut occupied = occupied(lattice, points)?;
    occupied.retain(|&k| inside(&range, corner_of(k)));
    dilated_count(&occupied, -reach..=reach, &owned_range(lattice, core))
        .map_err(KernelError::failed)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plane(step: f64, side: f64) -> TilePoints {
        let n = (side / step) as usize;
        let points = (0..n * n)
            .map(|i| DVec3::new((i % n) as f64 * step, (i / n) as f64 * step, 0.0))
            .collect();
        TilePoints::whole(points)
    }

    /// The count equals the band built and filtered by ownership, for
    /// cores that cut the cloud, hold it whole or are unbounded.
    #[test]
    fn band_size_counts_the_owned_band() {
        use super::super::dilate::dilate;
        let lattice = Lattice::new(DVec3::new(0.3, -0.2, 0.1), 0.7).expect("lattice");
        let mut state = 99u64;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let points: Vec<DVec3> = (0..3000)
            .map(|_| {
                let (u, v) = (next() * 6.0, next() * 6.0);
                DVec3::new(u * 3.0, v * 2.0, (u * 0.7).sin() * 2.0 + next() * 0.3)
            })
            .collect();
        let cores = [
            Aabb::new(DVec3::new(4.0, 3.0, -1.0), DVec3::new(10.5, 8.0, 0.9)),
            Aabb::new(DVec3::splat(-50.0), DVec3::splat(50.0)),
            Aabb::new(DVec3::splat(f64::NEG_INFINITY), DVec3::splat(f64::INFINITY)),
        ];
        for core in &cores {
            for reach in [1, 3] {
                let range = cube_range(&lattice, core, reach);
                let mut occ = occupied(&lattice, &points).expect("occupied");
                occ.retain(|&k| inside(&range, corner_of(k)));
                let brute = dilate(&occ, -reach..=reach)
                    .expect("dilate")
                    .into_iter()
                    .filter(|&k| super::super::cubes::owns(&lattice, core, corner_of(k)))
                    .count() as u64;
                let got = band_size(&lattice, &points, core, reach).expect("count");
                assert_eq!(got, brute, "{core:?} {reach}");
                assert!(got > 0);
            }
        }
    }

    /// A sparse region needs nearly the band of a dense one over the same
    /// area: a budget by points alone let sparse tiles overrun `--mem`.
    #[test]
    fn a_sparse_tile_needs_the_bytes_of_its_band_not_of_its_points() {
        let kernel = ImplicitKernel {
            lattice: Lattice::new(DVec3::ZERO, 2.2).expect("lattice"),
            limit: f64::INFINITY,
            initial_margin: 0.0,
            band: 2,
            field: Field::Mls,
            spacing: 1.0,
            bytes_per_cube: BYTES_PER_CUBE,
            everywhere: None,
            flat_tolerance: 0.0,
        };
        let (dense, sparse) = (plane(1.0, 120.0), plane(3.0, 120.0));
        let bytes = |t: &TilePoints| kernel.bytes_for(t).expect("bytes");
        let per_point = |t: &TilePoints| bytes(t) as f64 / t.points.len() as f64;
        // Same area, a ninth of the points: the band (not the points) sets
        // most of the need, so the sparse tile needs over half the dense
        // tile's bytes and several times as much per point.
        assert!(
            bytes(&sparse) * 2 > bytes(&dense),
            "{} {}",
            bytes(&sparse),
            bytes(&dense)
        );
        assert!(per_point(&sparse) > 4.0 * per_point(&dense));
        // And the dense plane's need is its points' and its band's.
        let cubes = (120.0f64 / 2.2 + 1.0).powi(2) * 5.0;
        let expected = tile_bytes(dense.points.len() as u64, cubes as u64, BYTES_PER_CUBE) as f64;
        let got = bytes(&dense) as f64;
        assert!((got / expected - 1.0).abs() < 0.2, "{got} vs {expected}");
    }
}
