//! Streaming format conversion: any readable format to any writable one,
//! chunk by chunk, in input order. LAS output needs its quantisation before
//! the first point, so a source without header bounds is read twice.

use super::{
    create_writer, format_from_name, open_reader, AttributeSet, Format, IoError, PointChunk,
    ReadOptions, WriterSpec, DEFAULT_CHUNK,
};
use crate::geom::Aabb;
use crate::progress::Progress;
use std::path::Path;

/// What a conversion did.
#[derive(Clone, Copy, Debug, Default)]
pub struct ConvertStats {
    /// Points written (with `keep`, the unselected ones too).
    pub points: u64,
    /// Input records dropped (non-finite coordinates or a cut last line under the skip policy, or flagged invalid by the file).
    pub skipped: u64,
    /// Input records not processed: pixels without a return, points not
    /// selected (written flagged with `keep`, else not written).
    pub left_out: super::LeftOut,
    /// Attributes carried from the input to the output.
    pub carried: AttributeSet,
    /// Attributes of the input the output format cannot hold.
    pub dropped: AttributeSet,
}

/// `read` is an [`InvalidPolicy`](super::InvalidPolicy) or [`ReadOptions`].
pub fn convert(
    input: &Path,
    output: &Path,
    read: impl Into<ReadOptions>,
    progress: &dyn Progress,
) -> Result<ConvertStats, IoError> {
    convert_keeping(input, output, read, false, progress)
}

/// [`convert`]; with `keep`, the points `read`'s selection leaves out are
/// written too, in input order, flagged [`super::keep::UNSELECTED`] in a
/// `flags` column where the format has one.
pub fn convert_keeping(
    input: &Path,
    output: &Path,
    read: impl Into<ReadOptions>,
    keep: bool,
    progress: &dyn Progress,
) -> Result<ConvertStats, IoError> {
    let read: ReadOptions = read.into();
    let keep = keep && !read.select.is_all();
    let (format, _) = format_from_name(output).ok_or_else(|| IoError::UnknownFormat {
        path: output.to_path_buf(),
    })?;
    let mut reader = open_reader(input, &read)?;
    let info = reader.info().clone();
    let is_las = matches!(format, Format::Las | Format::Laz);
    let bounds = match (is_las, info.header_bounds, info.las_transform) {
        (true, None, None) => Some(scan_bounds(input, &read, progress)?),
        (_, b, _) => b,
    };
    let spec = WriterSpec {
        format,
        with_normals: info.has_normals,
        with_flags: keep,
        attributes: info.attributes.intersect(format.attributes()),
        bounds,
        las_transform: info.las_transform,
    };
    let mut writer = create_writer(output, &spec)?;
    if keep {
        writer = Box::new(super::keep::KeepUnselected::wrap(
            writer,
            output,
            input,
            &read,
            spec.with_normals,
            spec.with_flags,
            spec.attributes,
        )?);
    }
    let mut chunk = PointChunk::default();
    progress.begin("convert", info.declared_count.unwrap_or(0));
    while reader.read_chunk(&mut chunk, DEFAULT_CHUNK)? > 0 {
        writer.write_chunk(&chunk, None)?;
        progress.advance(chunk.len() as u64);
    }
    progress.end();
    let skipped = reader.skipped();
    let left_out = reader.left_out();
    let rows = writer.finish()?;
    Ok(ConvertStats {
        points: rows,
        skipped,
        left_out,
        carried: spec.attributes,
        dropped: info.attributes.without(spec.attributes),
    })
}

/// Bounding box of all points of `path`, by one streaming pass.
pub(crate) fn scan_bounds(
    path: &Path,
    read: impl Into<ReadOptions>,
    progress: &dyn Progress,
) -> Result<Aabb, IoError> {
    let mut reader = open_reader(path, read)?;
    let mut chunk = PointChunk::default();
    let mut bounds = Aabb::EMPTY;
    progress.begin("bounds", reader.info().declared_count.unwrap_or(0));
    while reader.read_chunk(&mut chunk, DEFAULT_CHUNK)? > 0 {
        chunk.xyz.iter().for_each(|p| bounds.add(*p));
        progress.advance(chunk.len() as u64);
    }
    progress.end();
    Ok(bounds)
}
