//! The seam pass of the local-projection kernel (`kernel.rs`): the bands
//! along tile faces, left empty by the tiles, are re-grown with the tiles'
//! fixed triangles as they are. Their open vertices start as the FRINGE
//! front (section 2.3), in input-id order; the band's still-free points
//! then seed in input-id order. The growth is the tiles' own
//! (`grow.rs`), over the frame points every tile handed over, so the
//! stitched mesh obeys the same rules across seams: no crack the growth
//! could close, no overlap, no duplicate, one winding.
//!
//! The pass runs once, after every tile, on one thread: its cost is that of
//! the frame, a few spacings along each tile face.

use super::cloud::{Cloud, Csr};
use super::grow::Grower;
use super::kernel::ProjectionTile;
use super::orient::{flipped, volume6};
use super::params::ProjectionParams;
use super::surface::{State, Surface};
use crate::spatial::{GridIndex, IndexError};
use glam::DVec3;

/// The frames of all tiles, gathered in tile order.
#[derive(Default)]
pub struct SeamBuilder {
    store: Vec<u32>,
    ids: Vec<u64>,
    points: Vec<DVec3>,
    normals: Vec<DVec3>,
    spacing: Vec<f64>,
    unused: Vec<bool>,
    centre: Vec<bool>,
    /// Neighbour lists by store index.
    hoods: Csr,
    /// Fixed triangles reaching into the frames, and their global pieces.
    fixed: Vec<[u32; 3]>,
    fixed_piece: Vec<u32>,
    ghosts: Vec<(u32, DVec3)>,
}

/// The triangles the seam pass added (store indices) with their pieces,
/// and each global piece's place in the seam's pieces.
pub struct SeamResult {
    pub triangles: Vec<[u32; 3]>,
    /// Root and flip (relative to the root) of each triangle, in the seam's
    /// piece numbering: tiles' pieces `0..pieces`, then new ones.
    pub orientation: Vec<(u32, bool)>,
    /// Six times the signed volume of each added triangle, wound in its
    /// root's frame, about the store origin.
    pub volumes: Vec<f64>,
    /// Root and flip of each tile piece `0..pieces`.
    pub piece_roots: Vec<(u32, bool)>,
    /// Elements of the seam's pieces (roots are below this).
    pub elements: usize,
    pub processed: u64,
}

impl SeamBuilder {
    /// Adds one tile's frame; its pieces are numbered from `first_piece`.
    pub fn add(&mut self, tile: &ProjectionTile, first_piece: u32) {
        let mut start = 0;
        for f in &tile.frame {
            self.store.push(f.store);
            self.ids.push(f.id);
            self.points.push(f.p);
            self.normals.push(f.normal);
            self.spacing.push(f.spacing);
            self.unused.push(f.unused);
            self.centre.push(f.centre);
            let end = f.hood_end as usize;
            self.hoods.items.extend_from_slice(&tile.hoods[start..end]);
            self.hoods.ends.push(self.hoods.items.len() as u32);
            start = end;
        }
        for &k in &tile.frame_triangles {
            self.fixed.push(tile.fixed[k as usize]);
            self.fixed_piece
                .push(first_piece + tile.fixed_piece[k as usize]);
        }
        self.ghosts.extend_from_slice(&tile.ghosts);
    }

    /// Re-grows the bands; `pieces` is the number of tile pieces.
    pub fn grow(
        mut self,
        params: &ProjectionParams,
        pieces: u32,
    ) -> Result<SeamResult, IndexError> {
        let frame_len = self.store.len();
        for &(store, p) in &self.ghosts {
            self.store.push(store);
            // Ghosts are never processed; their tie key only has to be
            // distinct from every input id.
            self.ids.push(u64::MAX - u64::from(store));
            self.points.push(p);
            self.normals.push(DVec3::ZERO);
            self.spacing.push(0.0);
            self.unused.push(false);
            self.centre.push(false);
            self.hoods.ends.push(self.hoods.items.len() as u32);
        }
        let local = LocalIndex::new(&self.store);
        let hoods = local.remap(&self.hoods);
        let mut s = Surface::with_pieces(self.store.len(), pieces);
        for (t, &piece) in self.fixed.iter().zip(&self.fixed_piece) {
            if let Some(t) = local.triangle(*t) {
                s.push(t, piece);
            }
        }
        let fixed_count = s.tris.len();
        let index = GridIndex::new(&self.points, &self.ids)?;
        let cloud = Cloud {
            points: &self.points,
            normals: &self.normals,
            spacing: &self.spacing,
            hoods: &hoods,
            centre: &self.centre,
            ids: &self.ids,
            index: &index,
        };
        let mut order: Vec<u32> = (0..frame_len as u32).collect();
        order.sort_unstable_by_key(|&i| self.ids[i as usize]);
        let mut grower = Grower::new(params, self.store.len());
        for i in 0..self.store.len() {
            s.state[i] = if i >= frame_len {
                State::Completed
            } else if self.unused[i] {
                State::Unused
            } else if !s.has_triangles(i as u32) {
                State::Free
            } else if s.is_closed(i as u32) {
                State::Completed
            } else {
                State::Fringe
            };
        }
        for &i in &order {
            if s.state[i as usize] == State::Fringe {
                grower.enqueue(i);
            }
        }
        grower.grow(&cloud, &mut s, &order);
        let triangles = s.tris[fixed_count..]
            .iter()
            .map(|t| t.map(|v| self.store[v as usize]))
            .collect();
        let orientation: Vec<(u32, bool)> = (fixed_count..s.tris.len())
            .map(|t| s.orientation(t as u32))
            .collect();
        let volumes = s.tris[fixed_count..]
            .iter()
            .zip(&orientation)
            .map(|(&t, &(_, flip))| {
                volume6(&self.points, if flip { flipped(t) } else { t }, DVec3::ZERO)
            })
            .collect();
        let piece_roots = (0..pieces).map(|p| s.pieces.find(p)).collect();
        Ok(SeamResult {
            triangles,
            orientation,
            volumes,
            piece_roots,
            elements: s.pieces.len(),
            processed: grower.processed,
        })
    }
}

/// Store index -> seam-local index, by binary search in the sorted
/// store indices.
struct LocalIndex {
    sorted: Vec<(u32, u32)>,
}

impl LocalIndex {
    fn new(store: &[u32]) -> Self {
        let mut sorted: Vec<(u32, u32)> = store.iter().copied().zip(0..).collect();
        sorted.sort_unstable();
        LocalIndex { sorted }
    }

    fn get(&self, store: u32) -> Option<u32> {
        self.sorted
            .binary_search_by_key(&store, |e| e.0)
            .ok()
            .map(|k| self.sorted[k].1)
    }

    fn triangle(&self, t: [u32; 3]) -> Option<[u32; 3]> {
        Some([self.get(t[0])?, self.get(t[1])?, self.get(t[2])?])
    }

    /// The lists with store indices turned local; neighbours outside the
    /// seam set are dropped (only non-centres have any).
    fn remap(&self, hoods: &Csr) -> Csr {
        let mut out = Csr::default();
        let mut start = 0;
        for &end in &hoods.ends {
            for &j in &hoods.items[start as usize..end as usize] {
                if let Some(l) = self.get(j) {
                    out.items.push(l);
                }
            }
            out.ends.push(out.items.len() as u32);
            start = end;
        }
        out
    }
}
