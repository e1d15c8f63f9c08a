//! Which points are isolated outliers, for the orientation's decisions: a
//! point whose nearest neighbour lies beyond 3x the cloud's 99th percentile
//! of nearest-neighbour distances (the points `SamplingStats::rho_outliers`
//! counts). Its tangent plane is fitted to neighbours it is not part of, so
//! its normal is noise; the orientation still signs it with its component
//! but lets it decide nothing.
//!
//! The cut is a property of the whole cloud, known only once every tile's
//! histogram is merged, so the normals kernel hands back each core point's
//! distance as the histogram slot it counted it in, kept here in a scratch
//! column (2 bytes a point) until the orientation has read it. Slots are
//! exact per point (tiling-free distances, one histogram scale), and the
//! merged histogram is the same for every tiling, so the verdict is too.

use crate::normals::NormalsError;
use crate::store::sampling::LogHistogram;
use crate::store::{Column, PointStore, StoreError, TileEntry};

/// Scratch column of the slots, beside the store's columns.
const SLOTS_FILE: &str = ".orient.nn";

/// The points' nearest-neighbour slots and the first slot of the isolated.
pub struct Isolated {
    column: Column,
    _cleanup: crate::io::cleanup::Registered,
    /// The first isolated slot; `u16::MAX` (nobody) until [`Self::settle`].
    from: u16,
}

impl Isolated {
    /// An empty column for `store`'s points.
    pub fn create(store: &PointStore) -> Result<Self, NormalsError> {
        let path = store.dir().join(SLOTS_FILE);
        Ok(Isolated {
            _cleanup: crate::io::cleanup::register(&path),
            column: Column::create(&path, 2, store.len())?,
            from: u16::MAX,
        })
    }

    /// Writes the slots of the points from store index `start` on.
    pub fn write(&self, start: u64, slots: &[u16]) -> Result<(), StoreError> {
        let bytes: Vec<u8> = slots.iter().flat_map(|s| s.to_le_bytes()).collect();
        self.column.write_bytes(start, &bytes)
    }

    /// Sets the cut from the whole cloud's nearest-neighbour histogram
    /// (the one the slots were counted in) and the limit beyond which a
    /// distance is isolated.
    pub fn settle(&mut self, nn: &LogHistogram, limit: f64) {
        self.from = nn.outliers_from(limit);
    }

    /// Whether each point of tile `t` is isolated, in store order.
    pub fn read_tile(&self, t: &TileEntry, out: &mut Vec<bool>) -> Result<(), StoreError> {
        out.clear();
        let from = self.from;
        self.column.with_bytes(t.start, t.count, |b| {
            out.extend(
                b.chunks_exact(2)
                    .map(|c| u16::from_le_bytes([c[0], c[1]]) >= from),
            )
        })
    }
}

impl Drop for Isolated {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(self.column.path());
    }
}
