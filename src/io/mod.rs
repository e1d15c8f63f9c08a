//! Point-cloud formats: streaming, chunked readers and writers for PLY
//! (ASCII, binary LE/BE, gzip), XYZ/CSV text (gzip), LAS/LAZ, PCD and E57.
//!
//! Readers hand out [`PointChunk`]s of bounded size, so no format ever needs the
//! whole file in memory. Coordinates are validated once here (finite, counts
//! consistent with headers, no data past the declared end, no text record
//! on a last line cut short), so nothing downstream checks again.

pub mod atomic;
pub(crate) mod attributes;
pub mod cleanup;
pub mod convert;
pub mod e57;
pub(crate) mod error;
pub mod inspect;
pub mod keep;
pub(crate) mod las;
mod las_extra;
pub(crate) mod las_file;
pub mod memory;
pub(crate) mod obj;
pub(crate) mod open;
pub mod output;
pub(crate) mod pcd;
pub mod place;
pub(crate) mod ply;
mod policy;
mod reasons;
pub mod reclaim;
pub(crate) mod scratch;
pub mod select;
mod source;
mod text;
pub mod write;
pub(crate) mod xyz;

pub use atomic::AtomicFile;
pub use attributes::{
    Attribute, AttributeMaxima, AttributeSet, AttributeValues, Attributes, LasRecords,
};
pub use error::IoError;
pub use las_file::LasSource;
pub use obj::read_obj_mesh;
pub use open::{open_reader, open_stream_reader, read_all_xyz, read_mesh_any, read_mesh_from};
pub use output::{mesh_format, not_held, output_spec, Carried, MeshFormat};
pub use ply::read_mesh;
pub use reasons::{E57Reason, E57Step, LasReason, ScanProblem, Trailing, UnwritableReason};
pub use select::{LeftOut, Returns, Selection};
pub use write::{create_writer, create_writer_with, LasOutput};

use glam::{DVec3, Vec3};
use std::path::{Path, PathBuf};

/// Points handed out per chunk by default: large enough to amortise calls,
/// small enough (about 1 MiB) to keep ingest memory flat.
pub const DEFAULT_CHUNK: usize = 1 << 15;

/// File formats scanmesh reads and writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Format {
    /// PLY, ASCII encoding.
    PlyAscii,
    /// PLY, binary little-endian encoding.
    PlyBinaryLe,
    /// PLY, binary big-endian encoding.
    PlyBinaryBe,
    /// Text, one point per line: x y z, optionally followed by nx ny nz (`.xyz`, `.txt`, `.csv`).
    Xyz,
    /// ASPRS LAS (1.2 to 1.4).
    Las,
    /// LAS compressed with LASzip.
    Laz,
    /// PCL's Point Cloud Data: read as ASCII, binary or binary_compressed,
    /// written binary.
    Pcd,
    /// ASTM E2807: every scan read into the world frame by its pose;
    /// written as one scan of f64 coordinates.
    E57,
}

impl std::fmt::Display for Format {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Format::PlyAscii => "PLY (ASCII)",
            Format::PlyBinaryLe => "PLY (binary little-endian)",
            Format::PlyBinaryBe => "PLY (binary big-endian)",
            Format::Xyz => "XYZ text",
            Format::Las => "LAS",
            Format::Laz => "LAZ",
            Format::Pcd => "PCD",
            Format::E57 => "E57",
        })
    }
}

impl Format {
    /// The attributes this format can hold (README "Attributes").
    pub fn attributes(self) -> AttributeSet {
        match self {
            Format::PlyAscii
            | Format::PlyBinaryLe
            | Format::PlyBinaryBe
            | Format::Las
            | Format::Laz
            | Format::Pcd => AttributeSet::all(),
            Format::E57 => AttributeSet::of(&[Attribute::Intensity, Attribute::Rgb]),
            Format::Xyz => AttributeSet::EMPTY,
        }
    }

    /// Whether this format holds computed per-point values as named fields
    /// ([`WriterSpec::values`]): PLY properties, PCD fields, LAS extra
    /// bytes. XYZ text has no names for its columns (a reader takes the
    /// fourth to sixth as a normal), E57 no standard field for them.
    pub fn holds_values(self) -> bool {
        !matches!(self, Format::Xyz | Format::E57)
    }
}

/// A bounded batch of consecutive input records.
///
/// `first_index` is the 0-based input index of `xyz[0]`; the reader counts
/// records it skipped (see [`InvalidPolicy::Skip`]) so indices stay those of
/// the input file.
#[derive(Clone, Debug, Default)]
pub struct PointChunk {
    /// 0-based input index of `xyz[0]`.
    pub first_index: u64,
    /// Point positions.
    pub xyz: Vec<DVec3>,
    /// Present when the source carries normals (PLY nx/ny/nz, XYZ 6 columns).
    pub normals: Option<Vec<Vec3>>,
    /// Input index of each point when some records were skipped; `None`
    /// means `first_index + position`.
    pub indices: Option<Vec<u64>>,
    /// Intensity, colour and the other attributes the source carries
    /// ([`SourceInfo::attributes`]), one value per point each.
    pub attrs: Attributes,
    /// LAS/LAZ only: each point's number of returns (what a selection of
    /// last returns reads); empty for other formats.
    pub number_of_returns: Vec<u8>,
    /// Computed per-point values a writer's spec names
    /// ([`WriterSpec::values`]), that many per point, point after point;
    /// readers leave it empty.
    pub values: Vec<f32>,
}

impl PointChunk {
    /// Points in the chunk.
    pub fn len(&self) -> usize {
        self.xyz.len()
    }
    /// Whether the chunk holds no point.
    pub fn is_empty(&self) -> bool {
        self.xyz.is_empty()
    }
    pub(crate) fn clear(&mut self) {
        self.xyz.clear();
        if let Some(n) = &mut self.normals {
            n.clear();
        }
        if let Some(i) = &mut self.indices {
            i.clear();
        }
        self.attrs.clear();
        self.number_of_returns.clear();
        self.values.clear();
    }
    /// Input index of the `i`-th point of this chunk.
    pub fn index_of(&self, i: usize) -> u64 {
        match &self.indices {
            Some(ix) => ix[i],
            None => self.first_index + i as u64,
        }
    }
}

/// What a reader knows from the header, before reading any point.
#[derive(Clone, Debug)]
pub struct SourceInfo {
    /// The file read.
    pub path: PathBuf,
    /// The file's format.
    pub format: Format,
    /// Whether the file is gzip-compressed.
    pub gzip: bool,
    /// Point count the header declares (PLY, LAS); `None` for text formats.
    pub declared_count: Option<u64>,
    /// Whether the records carry normals.
    pub has_normals: bool,
    /// Per-point attributes the records carry (intensity, colour, ...).
    pub attributes: AttributeSet,
    /// Bounding box from the header, where the format stores one (LAS).
    pub header_bounds: Option<crate::geom::Aabb>,
    /// LAS scale and offset, so a LAS output can reuse them.
    pub las_transform: Option<LasTransform>,
}

/// LAS integer-coordinate transform: `x = xi * scale.x + offset.x`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LasTransform {
    /// Size of one integer coordinate step, per axis.
    pub scale: DVec3,
    /// Coordinate of integer 0, per axis.
    pub offset: DVec3,
}

/// What to do with records whose coordinates are NaN or infinite.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum InvalidPolicy {
    /// Fail with an error naming the file and record (the default).
    #[default]
    Reject,
    /// Drop the record and count it ([`PointReader::skipped`]); so too a
    /// text file's last line without end of line, which may be cut inside
    /// a number ([`IoError::CutShort`] under `Reject`).
    Skip,
}

/// How to read an input: what to do with non-finite coordinates, for a
/// file of several scans (E57) which scans to read (`None`: all), and
/// which points to process (by class and return).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ReadOptions {
    /// What to do with records whose coordinates are not finite.
    pub policy: InvalidPolicy,
    /// Scan indices, as `scanmesh info` lists them; read in file order.
    pub scans: Option<Vec<usize>>,
    /// The points handed out ([`Selection`]); the others are counted
    /// ([`PointReader::left_out`]).
    pub select: Selection,
}

impl From<InvalidPolicy> for ReadOptions {
    fn from(policy: InvalidPolicy) -> Self {
        ReadOptions {
            policy,
            ..ReadOptions::default()
        }
    }
}

impl From<&ReadOptions> for ReadOptions {
    fn from(read: &ReadOptions) -> Self {
        read.clone()
    }
}

/// A streaming source of points.
pub trait PointReader: Send {
    /// What the header says about the source.
    fn info(&self) -> &SourceInfo;
    /// Clears `chunk`, then fills it with up to `max` points. Returns the
    /// number read; 0 means the input is exhausted (and its declared count,
    /// if any, was met: a short file is an error, not an early 0, and so is
    /// data past the declared end, checked in the call that reads the last
    /// declared record).
    fn read_chunk(&mut self, chunk: &mut PointChunk, max: usize) -> Result<usize, IoError>;
    /// Records dropped so far: those with non-finite coordinates, or on a
    /// text file's last line without end of line, under
    /// [`InvalidPolicy::Skip`], and those the file itself flags as no point
    /// (E57's invalid states), under every policy.
    fn skipped(&self) -> u64;
    /// Records read but not handed out because they hold no point to
    /// process (an organised cloud's pixels without a return) or the
    /// read's [`Selection`] left them out, under every policy.
    fn left_out(&self) -> LeftOut {
        LeftOut::default()
    }
    /// Where the scanner stood for each run of records: an E57 file's
    /// scans by their poses' translations (ASTM E2807: the pose maps the
    /// scanner's own frame, whose origin is the scanner, into the world),
    /// in record order. Empty for a source that does not know (the
    /// default).
    fn stations(&self) -> Vec<ScanStation> {
        Vec::new()
    }
}

/// A run of consecutive input records one scanner position took.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScanStation {
    /// File-wide record number of the run's first record.
    pub first_record: u64,
    /// Records in the run, valid or not.
    pub records: u64,
    /// The scanner's position in the world frame (absolute coordinates).
    pub position: DVec3,
}

/// What a point writer is asked to produce.
#[derive(Clone, Debug)]
pub struct WriterSpec {
    /// The format to write.
    pub format: Format,
    /// Write each point's normal (nx, ny, nz as f32).
    pub with_normals: bool,
    /// Write a per-point `flags` byte (u8) property where the format allows.
    pub with_flags: bool,
    /// Computed values written after the normals, one f32 field each, in
    /// this order ([`PointChunk::values`]); formats that cannot hold them
    /// are refused ([`Format::holds_values`]).
    pub values: &'static [ValueField],
    /// Says what the file holds, where the format has a place for it (a
    /// PLY comment, a PCD comment line); `None`: "written by scanmesh".
    pub comment: Option<&'static str>,
    /// Rows whose flags share a bit with this mask are not written (0:
    /// every row is): `outliers --drop` writes the points the rule keeps.
    /// The spec must carry the flags.
    pub drop_flagged: u8,
    /// The number of points to be written, when known before the first:
    /// a PLY header then states it plainly (else a fixed-width count is
    /// patched at the end), and `finish` fails unless exactly that many
    /// were written.
    pub count: Option<u64>,
    /// Attributes to write; each must be one the format can hold
    /// ([`Format::attributes`]) and every chunk must carry.
    pub attributes: AttributeSet,
    /// Bounds of all points to be written, needed by LAS to choose its
    /// quantisation when no `las_transform` is given.
    pub bounds: Option<crate::geom::Aabb>,
    /// The LAS scale and offset to use (LAS only); `None` chooses one from `bounds`.
    pub las_transform: Option<LasTransform>,
}

impl WriterSpec {
    /// Positions only, in `format`; set the other fields with struct update
    /// syntax.
    pub fn new(format: Format) -> Self {
        WriterSpec {
            format,
            with_normals: false,
            with_flags: false,
            values: &[],
            comment: None,
            drop_flagged: 0,
            count: None,
            attributes: AttributeSet::EMPTY,
            bounds: None,
            las_transform: None,
        }
    }
}

/// One computed value per point that an output carries as a field of its
/// own: its name in the output and what it means (a LAS extra bytes
/// description holds 32 bytes of it).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ValueField {
    /// The field's name (a PLY property, a PCD field, a LAS extra bytes
    /// name: at most 32 bytes).
    pub name: &'static str,
    /// What the value is, at most 32 bytes.
    pub description: &'static str,
}

/// A streaming sink of points. Output goes to a temporary name and appears
/// under its final name only in [`PointWriter::finish`].
pub trait PointWriter: Send {
    /// `flags`, when the spec asked for them, has one byte per point.
    fn write_chunk(&mut self, chunk: &PointChunk, flags: Option<&[u8]>) -> Result<(), IoError>;
    /// Completes the output and renames it into place; returns the number of points written.
    fn finish(self: Box<Self>) -> Result<u64, IoError>;
}

/// Format implied by a file name (`.ply`, `.xyz`, `.txt`, `.csv`, `.las`,
/// `.laz`, `.pcd`, `.e57`, each optionally followed by `.gz` for text, PLY
/// and PCD).
pub fn format_from_name(path: &Path) -> Option<(Format, bool)> {
    let name = path.file_name()?.to_str()?.to_ascii_lowercase();
    let (stem, gz) = match name.strip_suffix(".gz") {
        Some(s) => (s.to_string(), true),
        None => (name, false),
    };
    let ext = stem.rsplit('.').next()?;
    let f = match ext {
        "ply" => Format::PlyBinaryLe,
        "xyz" | "txt" | "csv" | "pts" => Format::Xyz,
        "las" => Format::Las,
        "laz" => Format::Laz,
        "pcd" => Format::Pcd,
        "e57" => Format::E57,
        _ => return None,
    };
    Some((f, gz))
}
