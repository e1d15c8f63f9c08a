//! Argument groups that a command flattens into its own (or that several
//! share), each with its mapping onto the library's parameters: raw flags
//! in, validated parameters out, errors naming the flags.

mod fit;
mod orient;
mod recon;
mod thresholds;

pub use fit::FitArgs;
pub use orient::{HoodArgs, OrientArgs};
pub use recon::ReconArgs;
pub use thresholds::Thresholds;
