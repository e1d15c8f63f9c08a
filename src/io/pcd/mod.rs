//! PCD, the Point Cloud Library's format: the header (`header`), the
//! streaming reader (`read`) for ASCII, binary and binary_compressed bodies
//! (LZF, `lzf`). Binary PCD is written by the PLY writer (same records).

mod header;
mod lzf;
mod read;

pub use read::PcdReader;

/// Whether `magic` (a file's first bytes) starts a PCD header: PCL's
/// comment line, or a header keyword when the comment is missing.
pub fn is_pcd_magic(magic: &[u8]) -> bool {
    [&b"# .PCD"[..], b"VERSION", b"FIELDS "]
        .iter()
        .any(|m| magic.starts_with(m))
}
