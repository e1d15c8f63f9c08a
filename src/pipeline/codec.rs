//! How a tile kernel's result is saved and read back, so a resumable run
//! (`--run-dir`) reuses finished tiles instead of recomputing them. The
//! encoding is postcard's (compact, exact for floats): a decoded result is
//! the computed one, so a resumed run writes the same bytes.

use serde::de::DeserializeOwned;
use serde::Serialize;

/// Encoder and decoder of a kernel's `Output`.
pub struct Codec<O> {
    /// Serialises a tile result.
    pub encode: fn(&O) -> Result<Vec<u8>, postcard::Error>,
    /// Reads a tile result back; an error means the saved bytes are damaged.
    pub decode: fn(&[u8]) -> Result<O, postcard::Error>,
}

impl<O: Serialize + DeserializeOwned> Codec<O> {
    /// The serde encoding of `O`.
    pub fn serde() -> Self {
        Codec {
            encode: |o| postcard::to_stdvec(o),
            decode: |b| postcard::from_bytes(b),
        }
    }
}
