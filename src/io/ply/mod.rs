//! PLY (Turk's polygon file format): a streaming point reader for ASCII,
//! binary little- and big-endian bodies, and a whole-mesh reader for ground
//! truth meshes.

pub(crate) mod header;

mod attrs;
mod binary;
mod mesh;
mod read;
mod record;

pub use mesh::read_mesh;
pub(crate) use mesh::read_ply_mesh;
pub use read::PlyPointReader;

/// True when `magic` starts a PLY file (`ply` then LF or CR LF).
pub(crate) fn is_ply_magic(magic: &[u8]) -> bool {
    magic.starts_with(b"ply\n") || magic.starts_with(b"ply\r\n")
}
