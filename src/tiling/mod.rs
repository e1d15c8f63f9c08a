//! Tiles: the planner that splits space into core boxes, and the loader that
//! gathers a tile's core points plus the margin points of its neighbours.

pub mod load;
pub mod planner;

pub use load::{load_tile, TilePoints};
pub use planner::{plan_tiles, CellCount, PlannedTile, TilePlan};
