//! Argument groups that a command flattens into its own (or that several
//! share), each with its mapping onto the library's parameters: raw flags
//! in, validated parameters out, errors naming the flags.

mod fit;
mod orient;
mod planned;
mod recon;
mod thresholds;
mod tiles;

pub use fit::FitArgs;
pub use orient::{HoodArgs, Knn, OrientArgs};
pub use planned::Planned;
pub use recon::ReconArgs;
pub use thresholds::Thresholds;
pub use tiles::{parse_range, parse_share};
