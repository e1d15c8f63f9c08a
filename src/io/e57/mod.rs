//! E57 (ASTM E2807), the exchange format of terrestrial laser scanners,
//! through the `e57` crate: the scans' descriptions (`scan`), the
//! streaming reader of every selected scan in the world frame (`read`),
//! and a one-scan writer ([`write`]). `seekbuf` keeps the crate's page
//! reads buffered.
//!
//! Intensity and colour are not carried: points leave the io layer as
//! coordinates (and normals) only, for every format, until the store
//! gains attribute columns.

mod read;
mod scan;
mod seekbuf;
mod write;

pub use read::E57Reader;
pub use scan::{Pose, ScanInfo};
pub(crate) use write::E57Writer;

use super::IoError;
use std::path::Path;

/// The file signature every E57 starts with.
const MAGIC: &[u8] = b"ASTM-E57";

/// Whether `magic` (a file's first bytes) is an E57 signature.
pub fn is_e57_magic(magic: &[u8]) -> bool {
    magic.starts_with(MAGIC)
}

/// The scans of the E57 at `path`, from its header and XML section alone
/// (no point is decoded).
pub fn list_scans(path: &Path) -> Result<Vec<ScanInfo>, IoError> {
    read::open_file(path).map(|(_, scans)| scans)
}
