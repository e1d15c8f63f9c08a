//! Streaming point writers: binary PLY (LE/BE), ASCII PLY, XYZ text,
//! LAS/LAZ, and E57 ([`crate::io::e57`]). Every writer goes through [`AtomicFile`]: the
//! output appears under its final name only in `finish`; a writer dropped
//! before that leaves nothing behind.

mod dropping;
mod las;
mod ply;
mod xyz;

pub use las::{choose_las_transform, LasOutput};

use super::{AtomicFile, Attributes, Format, IoError, PointChunk, PointWriter, WriterSpec};
use glam::Vec3;
use std::fs::File;
use std::io::BufWriter;
use std::path::Path;

/// Output buffer: few, large writes.
const OUT_BUF: usize = 1 << 20;

/// Creates a writer for `spec.format` at `path` (a `.laz` path, or
/// `Format::Laz`, gives compressed LAS). gzip output is not offered.
pub fn create_writer(path: &Path, spec: &WriterSpec) -> Result<Box<dyn PointWriter>, IoError> {
    create_writer_with(path, spec, &LasOutput::default())
}

/// [`create_writer`], with what a LAS/LAZ output is made from (a LAS input
/// written as it came, a point format, the largest values); other formats
/// ignore `las`.
pub fn create_writer_with(
    path: &Path,
    spec: &WriterSpec,
    las: &LasOutput,
) -> Result<Box<dyn PointWriter>, IoError> {
    let name = path.to_string_lossy().to_ascii_lowercase();
    if name.ends_with(".gz") {
        return Err(IoError::Unsupported {
            path: path.to_path_buf(),
            reason: "gzip output is not supported; compress the finished file".into(),
        });
    }
    if !spec.values.is_empty() && !spec.format.holds_values() {
        let names: Vec<&str> = spec.values.iter().map(|v| v.name).collect();
        return Err(IoError::Unsupported {
            path: path.to_path_buf(),
            reason: format!(
                "this format has no named field for {}; write .ply, .pcd, .las or .laz",
                names.join(", ")
            ),
        });
    }
    let unheld = spec.attributes.without(spec.format.attributes());
    if !unheld.is_empty() {
        return Err(IoError::Unsupported {
            path: path.to_path_buf(),
            reason: format!("this format cannot hold {}", unheld.describe()),
        });
    }
    if spec.drop_flagged != 0 {
        if !spec.with_flags {
            return Err(IoError::Unsupported {
                path: path.to_path_buf(),
                reason: "rows can be left out by their flags only where the flags are written"
                    .into(),
            });
        }
        // How many rows are left is known only at the end.
        let inner = WriterSpec {
            drop_flagged: 0,
            count: None,
            ..spec.clone()
        };
        let writer = create_writer_with(path, &inner, las)?;
        return Ok(Box::new(dropping::DropFlagged::new(writer, path, spec)));
    }
    Ok(match spec.format {
        Format::PlyAscii | Format::PlyBinaryLe | Format::PlyBinaryBe | Format::Pcd => {
            Box::new(ply::PlyWriter::create(path, spec)?)
        }
        Format::Xyz => Box::new(xyz::XyzWriter::create(path, spec)?),
        Format::Las | Format::Laz => {
            let compressed = spec.format == Format::Laz || name.ends_with(".laz");
            Box::new(las::LasWriter::create(path, spec, las, compressed)?)
        }
        Format::E57 => Box::new(super::e57::E57Writer::create(path, spec)?),
    })
}

/// The temporary output and a buffered handle on it (a second descriptor of
/// the same open file, so `AtomicFile` keeps the commit/cleanup duty).
fn open_output(path: &Path) -> Result<(AtomicFile, BufWriter<File>), IoError> {
    let mut atomic = AtomicFile::create(path)?;
    let file = atomic
        .file()
        .try_clone()
        .map_err(|e| IoError::os(path, e))?;
    Ok((atomic, BufWriter::with_capacity(OUT_BUF, file)))
}

/// Fails unless a writer given a known count ([`WriterSpec::count`])
/// wrote exactly that many points; called before the output is committed,
/// so a short output never appears under its name.
pub(crate) fn check_count(path: &Path, spec: &WriterSpec, written: u64) -> Result<(), IoError> {
    match spec.count {
        Some(declared) if declared != written => Err(IoError::Unsupported {
            path: path.to_path_buf(),
            reason: format!("{written} points written where {declared} were declared"),
        }),
        _ => Ok(()),
    }
}

/// What a chunk carries for the spec: normals, values and flags, each
/// present exactly when the spec asks for it.
pub(crate) struct Checked<'a> {
    normals: Option<&'a [Vec3]>,
    /// `spec.values.len()` values per point.
    values: Option<&'a [f32]>,
    /// Values per point.
    per: usize,
    flags: Option<&'a [u8]>,
    /// The chunk's attributes, when the spec asks for some (the spec's
    /// set says which to write).
    attrs: Option<&'a Attributes>,
    set: super::AttributeSet,
}

impl Checked<'_> {
    /// Point `i`'s computed values (none when the spec asks for none).
    #[inline]
    pub(crate) fn values_of(&self, i: usize) -> &[f32] {
        match self.values {
            Some(v) => &v[self.per * i..self.per * (i + 1)],
            None => &[],
        }
    }
}

/// Checks `chunk` against `spec`; `written` is the number of points already
/// written, so errors name the output record.
pub(crate) fn check_chunk<'a>(
    path: &Path,
    spec: &WriterSpec,
    chunk: &'a PointChunk,
    flags: Option<&'a [u8]>,
    written: u64,
) -> Result<Checked<'a>, IoError> {
    let n = chunk.len();
    let misuse = |reason: String| IoError::Unsupported {
        path: path.to_path_buf(),
        reason,
    };
    let normals = match (spec.with_normals, chunk.normals.as_deref()) {
        (false, _) => None,
        (true, Some(nv)) if nv.len() == n => Some(nv),
        (true, _) => return Err(misuse(format!("writer needs {n} normals for this chunk"))),
    };
    let flags = match (spec.with_flags, flags) {
        (false, _) => None,
        (true, Some(f)) if f.len() == n => Some(f),
        (true, _) => return Err(misuse(format!("writer needs {n} flags for this chunk"))),
    };
    let per = spec.values.len();
    let values = match (per, chunk.values.len()) {
        (0, _) => None,
        (_, got) if got == n * per => Some(chunk.values.as_slice()),
        (_, got) => {
            return Err(misuse(format!(
                "writer needs {} values for this chunk, it has {got}",
                n * per
            )))
        }
    };
    let attrs = match spec.attributes.is_empty() {
        true => None,
        false => Some(&chunk.attrs),
    };
    for a in spec.attributes.iter() {
        if chunk.attrs.len_of(a) != n {
            return Err(misuse(format!(
                "writer needs {n} {} values for this chunk, it has {}",
                a.name(),
                chunk.attrs.len_of(a)
            )));
        }
    }
    for (i, p) in chunk.xyz.iter().enumerate() {
        if let Some(value) = [p.x, p.y, p.z].into_iter().find(|c| !c.is_finite()) {
            return Err(IoError::NonFinite {
                path: path.to_path_buf(),
                record: written + i as u64,
                value,
            });
        }
    }
    Ok(Checked {
        normals,
        values,
        per,
        flags,
        attrs,
        set: spec.attributes,
    })
}
