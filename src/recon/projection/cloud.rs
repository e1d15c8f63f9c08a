//! What the growth reads about the points (plain data, no tiles): positions,
//! PCA normals, local spacings, neighbour lists, and which points may be
//! processed as centres.

use super::probe::Probe;
use crate::normals::hood::Hoods;
use glam::DVec3;

/// Neighbour lists by point (local indices, nearest first).
pub trait Neighbourhoods: Sync {
    fn get(&self, i: u32) -> &[u32];
}

impl Neighbourhoods for Hoods {
    fn get(&self, i: u32) -> &[u32] {
        Hoods::get(self, i as usize)
    }
}

/// Lists end to end: `ends[i]` is where point i's list ends.
#[derive(Clone, Debug, Default)]
pub struct Csr {
    pub ends: Vec<u32>,
    pub items: Vec<u32>,
}

impl Neighbourhoods for Csr {
    fn get(&self, i: u32) -> &[u32] {
        let i = i as usize;
        let start = if i == 0 { 0 } else { self.ends[i - 1] as usize };
        &self.items[start..self.ends[i] as usize]
    }
}

pub struct Cloud<'a, H: Neighbourhoods> {
    pub points: &'a [DVec3],
    /// Unit PCA normal, unoriented (zero when the plane is undetermined).
    pub normals: &'a [DVec3],
    /// Local spacing (`thin.rs`).
    pub spacing: &'a [f64],
    pub hoods: &'a H,
    /// Whether a point may be processed as a centre (its neighbourhood is
    /// complete); others can still be connected to.
    pub centre: &'a [bool],
    /// Whether a point may be a corner of a new triangle (a lattice job
    /// adds triangles only inside its window, `lattice.rs`).
    pub joinable: &'a [bool],
    /// Clearance a new triangle keeps from the triangles near it, beyond
    /// what they share: how far the rounding of the kernel's coordinates
    /// may move them (`PointStore::rounding_reach`; 0 for points that are
    /// written as they are).
    pub slack: f64,
    /// Every point within a ball, for checks beyond a neighbour list.
    pub probe: &'a Probe<'a>,
}
