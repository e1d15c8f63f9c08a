//! The normals' output: every format of the output table that holds
//! normals, with the flags where it holds them.

use crate::io::{output_spec, Carried, IoError, WriterSpec};
use std::path::Path;

/// The writer spec for normals written to `path` (`ascii`: a PLY as text);
/// a format that cannot hold normals is an error naming those that can.
pub fn normals_output(path: &Path, ascii: bool) -> Result<WriterSpec, IoError> {
    let carried = Carried {
        normals: true,
        flags: true,
        ..Carried::default()
    };
    output_spec(path, &carried, ascii)
}
