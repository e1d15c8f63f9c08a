//! The pair graph of one cloud in memory, for [`super::orient_by_sources`]:
//! every pair in a point's neighbourhood (within `r`, or among its k
//! nearest) or among its `bridge_k` nearest (the nearest-distance rule's
//! reach beyond `r`), made symmetric, as compressed adjacency lists. The
//! tile kernel enumerates the same pairs from each core point instead.

use super::hood::Hoods;
use super::{Neighbourhood, SourceParams, SourcesError};
use crate::spatial::{KdIndex, KnnIndex, Neighbour};
use glam::DVec3;

pub(crate) struct Graph {
    start: Vec<usize>,
    nbrs: Vec<u32>,
}

impl Graph {
    /// Pairs between points that both have a normal.
    pub(crate) fn build(
        points: &[DVec3],
        normals: &[Option<DVec3>],
        ids: &[u64],
        params: &SourceParams,
    ) -> Result<Self, SourcesError> {
        let hoods = Hoods::build(params.hood, points, ids)?;
        let bridge = match params.hood {
            Neighbourhood::Radius(_) if params.bridge_k > 0 => Some(KdIndex::new(points, ids)?),
            _ => None,
        };
        let mut pairs: Vec<(u32, u32)> = Vec::new();
        let mut found: Vec<Neighbour> = Vec::new();
        for i in 0..points.len() {
            if normals[i].is_none() {
                continue;
            }
            hoods.of(i, &mut found);
            add_pairs(i, &found, normals, &mut pairs);
            if let Some(index) = &bridge {
                index.knn(points[i], params.bridge_k, Some(i as u32), &mut found);
                add_pairs(i, &found, normals, &mut pairs);
            }
        }
        pairs.sort_unstable();
        pairs.dedup();
        Ok(Self::from_pairs(points.len(), &pairs))
    }

    fn from_pairs(n: usize, pairs: &[(u32, u32)]) -> Self {
        let mut start = vec![0usize; n + 1];
        for &(a, b) in pairs {
            start[a as usize + 1] += 1;
            start[b as usize + 1] += 1;
        }
        for i in 0..n {
            start[i + 1] += start[i];
        }
        let mut fill = start.clone();
        let mut nbrs = vec![0u32; start[n]];
        for &(a, b) in pairs {
            nbrs[fill[a as usize]] = b;
            fill[a as usize] += 1;
            nbrs[fill[b as usize]] = a;
            fill[b as usize] += 1;
        }
        Graph { start, nbrs }
    }

    /// The points paired with `i`.
    pub(crate) fn of(&self, i: usize) -> &[u32] {
        &self.nbrs[self.start[i]..self.start[i + 1]]
    }
}

fn add_pairs(
    i: usize,
    found: &[Neighbour],
    normals: &[Option<DVec3>],
    pairs: &mut Vec<(u32, u32)>,
) {
    for nb in found {
        let j = nb.index as usize;
        if j != i && normals[j].is_some() {
            pairs.push((i.min(j) as u32, i.max(j) as u32));
        }
    }
}
