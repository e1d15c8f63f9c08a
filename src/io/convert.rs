//! Streaming format conversion: any readable format to any writable one,
//! chunk by chunk, in input order. LAS output needs its quantisation before
//! the first point, so a source without header bounds is read twice. A LAS
//! input written to LAS is written as it came (its own records, header
//! fields, VLRs and EVLRs: [`super::LasOutput::source`]); written to any
//! other format, its colour is first read whole to tell 8-bit colour in
//! 16-bit fields from 16-bit colour, as it must be known before the first
//! point is written.

use super::{
    create_writer_with, open_reader, Attribute, AttributeMaxima, AttributeSet, Format, IoError,
    LasOutput, LasSource, PointChunk, ReadOptions, WriterSpec, DEFAULT_CHUNK,
};
use crate::geom::Aabb;
use crate::progress::Progress;
use std::path::Path;
use std::sync::Arc;

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

impl std::fmt::Display for crate::summary::Summary<'_, ConvertStats> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let r = self.report;
        write!(
            f,
            "convert: {} points ({} skipped), attributes: {}, in {:.2} s, peak {} -> {}",
            r.points,
            r.skipped,
            r.carried.describe(),
            self.secs,
            self.peak_text(),
            self.output.display()
        )
    }
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
    // The output table decides the format; the input's normals are
    // carried where it holds them, not required.
    let carried = super::Carried {
        flags: keep,
        ..super::Carried::default()
    };
    let format = super::output_spec(output, &carried, false)?.format;
    if keep && !format.holds_flags() {
        return Err(IoError::Unsupported {
            path: output.to_path_buf(),
            reason: format!(
                "{format} has no named flags field to mark the unselected points \
                 (--unselected keep); write .ply, .pcd, .las or .laz"
            ),
        });
    }
    let mut reader = open_reader(input, &read)?;
    let info = reader.info().clone();
    let is_las = matches!(format, Format::Las | Format::Laz);
    // A LAS output of another format needs its quantisation, and its
    // point format is the smallest that holds the largest values: one
    // pass finds both (a header's bounds spare it).
    let (bounds, largest) = match (is_las, info.header_bounds, info.las_transform) {
        (true, None, None) => {
            let (b, m) = scan_bounds_and_maxima(input, &read, progress)?;
            (Some(b), Some(m))
        }
        (_, b, _) => (b, None),
    };
    let spec = WriterSpec {
        format,
        with_normals: info.has_normals && format.holds_normals(),
        with_flags: keep,
        attributes: info.attributes.intersect(format.attributes()),
        bounds,
        las_transform: info.las_transform,
        ..WriterSpec::new(format)
    };
    let las_in = matches!(info.format, Format::Las | Format::Laz);
    let las = match (las_in, is_las) {
        (true, true) => LasOutput {
            source: Some(Arc::new(LasSource::read(input)?)),
            ..LasOutput::default()
        },
        _ => LasOutput {
            largest,
            ..LasOutput::default()
        },
    };
    // LAS colour of at most 255 everywhere is 8-bit colour (PDAL's rule).
    let widen = las_in
        && !is_las
        && spec.attributes.contains(Attribute::Rgb)
        && scan_bounds_and_maxima(input, &read, progress)?
            .1
            .eight_bit_colour();
    let mut writer = create_writer_with(output, &spec, &las)?;
    if keep {
        writer = Box::new(super::keep::KeepUnselected::wrap(
            writer, output, input, &read, &spec,
        )?);
    }
    let mut chunk = PointChunk::default();
    progress.begin("convert", info.declared_count.unwrap_or(0));
    while reader.read_chunk(&mut chunk, DEFAULT_CHUNK)? > 0 {
        if widen {
            chunk.attrs.widen_8bit_colour();
        }
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

/// Bounding box and largest attribute values of all points of `path`, by
/// one streaming pass.
pub(crate) fn scan_bounds_and_maxima(
    path: &Path,
    read: impl Into<ReadOptions>,
    progress: &dyn Progress,
) -> Result<(Aabb, AttributeMaxima), IoError> {
    let mut reader = open_reader(path, read)?;
    let mut chunk = PointChunk::default();
    let mut bounds = Aabb::EMPTY;
    let mut maxima = AttributeMaxima::default();
    progress.begin("bounds", reader.info().declared_count.unwrap_or(0));
    while reader.read_chunk(&mut chunk, DEFAULT_CHUNK)? > 0 {
        chunk.xyz.iter().for_each(|p| bounds.add(*p));
        maxima.add(&chunk.attrs);
        progress.advance(chunk.len() as u64);
    }
    progress.end();
    Ok((bounds, maxima))
}
