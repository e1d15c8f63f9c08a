//! Which signed distance the lattice's corners and vertices take
//! ([`Field`]): the moving-least-squares field (`mls`, the default) or
//! paper 1's planes (`sdf`, `--plane sample`). The choice stands above
//! both fields, so `mls` can build on what `sdf` defines (the samples, a
//! corner's value) without `sdf` needing `mls` back.

use super::sdf::{signed_distance, Corner, Fit, Samples};
use crate::spatial::Neighbour;
use crate::tiling::TilePoints;
use glam::DVec3;

/// Which signed distance the corners and vertices take.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Field {
    /// The moving-least-squares average of nearby planes (`super::mls`),
    /// vertices moved onto its zero set along their lattice edges.
    #[default]
    #[value(help = "Moving least squares over the local spacing (issue 19)")]
    Mls,
    /// Paper 1 section 2.5: the nearest sample's plane (with `--closed`,
    /// `CLOSED_PLANES` averaged), vertices linearly interpolated.
    #[value(
        name = "sample",
        help = "Paper 1's definition: the nearest sample's tangent plane"
    )]
    Paper1,
}

impl Field {
    /// The field's value at lattice corner `p` (see [`signed_distance`]),
    /// with the sphere it fitted there (none for paper 1's planes).
    pub(crate) fn corner(
        self,
        s: &Samples,
        tile: &TilePoints,
        p: DVec3,
        limit: f64,
        nbr: &mut Vec<Neighbour>,
    ) -> (Corner, Fit) {
        match self {
            Field::Mls => super::mls::mls_corner(s, tile, p, limit, nbr),
            Field::Paper1 => (signed_distance(s, tile, p, limit, nbr), Fit::default()),
        }
    }
}
