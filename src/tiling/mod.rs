//! Tiles: the loader that gathers a tile's core points plus the margin
//! points of its neighbours. (The tiles themselves are planned when the
//! store is laid out: `store::tile_plan`.)

pub(crate) mod beyond;
pub(crate) mod load;

pub use beyond::{Beyond, Seen};
pub use load::{count_loaded, load_tile, MissingColumns, TileColumn, TilePoints, Values};
