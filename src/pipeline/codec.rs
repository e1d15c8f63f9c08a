//! How a tile kernel's result is saved and read back, so a resumable run
//! (`--run-dir`) reuses finished tiles instead of recomputing them. The
//! encoding is postcard's (compact, exact for floats): a decoded result is
//! the computed one, so a resumed run writes the same bytes.
//!
//! A saved result must also fit its tile before it is used: the file's
//! checksum says the bytes are those written, not that this run wrote
//! them for this tile, and the seam trusts what it gets (the fuzzer's
//! first finding: a forged forest edge naming point 12,692 of 2,000 ended
//! the run in a panic).

use crate::store::TileEntry;
use serde::de::DeserializeOwned;
use serde::Serialize;

/// Encoder and decoder of a kernel's `Output`.
pub struct Codec<O> {
    /// Serialises a tile result.
    pub encode: fn(&O) -> Result<Vec<u8>, postcard::Error>,
    /// Reads a tile result back; an error means the saved bytes are damaged.
    pub decode: fn(&[u8]) -> Result<O, postcard::Error>,
    /// Whether a decoded result fits `tile` of a store of `points` points
    /// (its counts, the ids it names, finite values); one that does not is
    /// recomputed like a damaged one.
    pub fits: fn(&O, &TileEntry, u64) -> bool,
}

impl<O: Serialize + DeserializeOwned> Codec<O> {
    /// The serde encoding of `O`, with the kernel's check of a result.
    pub fn serde(fits: fn(&O, &TileEntry, u64) -> bool) -> Self {
        Codec {
            encode: |o| postcard::to_stdvec(o),
            decode: |b| postcard::from_bytes(b),
            fits,
        }
    }
}
