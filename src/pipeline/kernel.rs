//! What a tile kernel is: a pure function from one tile's points (and the
//! store columns it declares it reads) to a result, which fails only when it
//! finds its margin short (the pipeline reloads the tile wider) or when the
//! tile cannot be processed at all.

use super::Codec;
use crate::store::{ColumnSpec, StoreError};
use crate::tiling::TilePoints;

/// Why a kernel could not finish a tile.
#[derive(Debug, thiserror::Error)]
pub enum KernelError {
    /// Some core point depends on points beyond the loaded region: the
    /// pipeline reloads the tile with at least `needed` margin and reruns it.
    #[error("margin too small: {needed} needed")]
    MarginTooSmall {
        /// The margin the kernel needs, in the store's coordinate units.
        needed: f64,
    },
    /// Reading the tile's points or columns from the store failed.
    #[error(transparent)]
    Store(#[from] StoreError),
    /// The tile cannot be processed; the fault says why.
    #[error(transparent)]
    Failed(#[from] TileFault),
    /// The tile cannot be processed; the typed error says why.
    #[error(transparent)]
    Source(Box<dyn std::error::Error + Send + Sync>),
}

/// Why a kernel cannot process a tile, where no typed error of a layer
/// below says it.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum TileFault {
    /// The crest test's radius indexes no grid over the tile's points.
    #[error("the crest test's radius {radius:e} indexes no grid over the tile's {points} points")]
    CrestRadius {
        /// The radius.
        radius: f64,
        /// Points loaded.
        points: usize,
    },
    /// The tile carries no curvature columns.
    #[error("the tile carries no curvature columns")]
    NoCurvature,
    /// The curvature radius indexes no grid.
    #[error("unusable curvature radius {radius}")]
    CurvatureRadius {
        /// The radius.
        radius: f64,
    },
    /// A point's index in the store does not fit a mesh's 32-bit indices.
    #[error("more than 2^32 points: mesh indices are 32-bit")]
    IndexTooLarge,
    /// A cut edge's corner has no value.
    #[error("a cut edge has an undefined corner")]
    UndefinedCorner,
    /// A cut edge's corner was never evaluated.
    #[error("a cut edge's corner was not evaluated")]
    CornerNotEvaluated,
    /// Not all corners of a corner's coarse cell were found.
    #[error("corner {corner:?}: its coarse cell's corners were not all found")]
    CoarseCorners {
        /// The corner, in lattice coordinates.
        corner: [i64; 3],
    },
}

impl KernelError {
    /// A typed error of the layer below, kept as it is.
    pub fn failed(e: impl std::error::Error + Send + Sync + 'static) -> Self {
        KernelError::Source(Box::new(e))
    }

    /// Ok when no dependence of a core point is short of the loaded region;
    /// else asks for the margin that makes the largest one complete:
    /// `margin + short`, a little more so rounding at the region's edge
    /// cannot loop, and twice the margin when the shortfall is unbounded
    /// (too few points loaded to tell how far it reaches). The one margin
    /// rule of every kernel.
    pub fn unless_short(short: f64, margin: f64) -> Result<(), KernelError> {
        if short <= 0.0 {
            return Ok(());
        }
        let needed = match short.is_finite() {
            true => (margin + short) * 1.0001 + 1e-12,
            false => margin * 2.0,
        };
        Err(KernelError::MarginTooSmall { needed })
    }
}

/// A pure function from one tile's points to a tile result.
pub trait TileKernel: Sync {
    /// The result of one tile, handed to the seam policy in tile order.
    type Output: Send;
    /// Stage name shown in progress, saved tiles' directory and errors: a
    /// literal (or a [`StageId`](crate::store::StageId)'s name), so an
    /// error keeps it without a copy.
    fn name(&self) -> &'static str;
    /// Margin to load first; the kernel asks for more when it finds it short.
    fn margin(&self) -> f64;
    /// Computes the tile's result from its core and margin points.
    fn run(&self, tile: &TilePoints) -> Result<Self::Output, KernelError>;
    /// Peak bytes per loaded point, for a kernel whose margin may grow on
    /// reload past the plan's allowance (`memory::plan::MARGIN_FACTOR`
    /// loaded points per core point): such a tile then waits until the
    /// memory of as many planned tiles is free. `None`: the plan's tile
    /// sizes hold.
    fn bytes_per_loaded_point(&self) -> Option<u64> {
        None
    }
    /// Peak bytes the kernel will hold running `tile`, when its need is not
    /// its loaded points times a constant (the marching cubes' grows with
    /// the cubes of its band, which a sparse region has many of per point):
    /// the tile then waits for that much of the plan's memory for tiles.
    /// `None`: the plan's tile sizes hold. Defaults to
    /// [`Self::bytes_per_loaded_point`] times the loaded points.
    fn bytes_for(&self, tile: &TilePoints) -> Option<u64> {
        self.bytes_per_loaded_point()
            .map(|b| b.saturating_mul(tile.points.len() as u64))
    }
    /// Bytes a tile of `points` loaded points holds before the kernel has
    /// looked at it, asked for before the load (the points are counted
    /// first, `tiling::count_loaded`) so a tile whose margin grew past the
    /// room is refused, or waits, without holding its points. `None`: the
    /// plan's tile sizes hold. Defaults to [`Self::bytes_per_loaded_point`]
    /// times the points; a kernel whose [`Self::bytes_for`] says more once
    /// it sees the tile is given the rest then, or loads again when the
    /// room has it.
    fn bytes_to_load(&self, points: u64) -> Option<u64> {
        self.bytes_per_loaded_point()
            .map(|b| b.saturating_mul(points))
    }
    /// The store columns the kernel reads: each tile carries their values
    /// for every loaded point (`TilePoints::column`).
    fn reads(&self) -> &[ColumnSpec] {
        &[]
    }
    /// How results are saved for a resumable run (`None`: recomputed).
    fn codec(&self) -> Option<Codec<Self::Output>> {
        None
    }
}
