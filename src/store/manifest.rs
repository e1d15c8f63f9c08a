//! The store manifest: the small JSON file that describes a point store
//! (counts, origin, bounds, spacing, tile table, columns, provenance).

use serde::{Deserialize, Serialize};

/// Bumped whenever the on-disk layout changes incompatibly.
/// (2: the input's exact coordinates, `xyz.input`, and checksums; 3: the
/// input order as u32, `index.u32`.)
pub(crate) const STORE_VERSION: u32 = 3;

/// File name of the manifest in a store directory.
pub const MANIFEST_FILE: &str = "manifest.json";

/// The store's description, kept as `manifest.json` in its directory.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Manifest {
    /// On-disk layout version; a store of another version is refused.
    pub version: u32,
    /// Points kept (the store index and the point index run over 0..count).
    pub count: u64,
    /// Input records dropped under `--skip-invalid`.
    pub skipped_invalid: u64,
    /// Input records not in the store because they hold no point to
    /// process or a selection left them out (absent in older stores: none).
    #[serde(default)]
    pub left_out: crate::io::LeftOut,
    /// Points that repeat another point's coordinates exactly (as stored).
    pub duplicates: u64,
    /// Coordinates are stored as f32 relative to this f64 origin.
    pub origin: [f64; 3],
    /// How the input's exact coordinates are kept (`xyz.input`, input
    /// order): what outputs write.
    pub coordinates: super::exact::Coordinates,
    /// Tight bounds of the input points (absolute, f64).
    pub bounds_min: [f64; 3],
    /// Upper corner of the input points' tight bounds (absolute, f64).
    pub bounds_max: [f64; 3],
    /// Mean nearest-neighbour distance estimated on a sample, if computed.
    pub spacing: Option<f64>,
    /// The histogram grid the tiles are cut from.
    pub grid: GridSpec,
    /// The tiles, in store order.
    pub tiles: Vec<TileEntry>,
    /// Attribute columns present besides coordinates and indices.
    pub columns: Vec<String>,
    /// The input's own per-point attributes, kept in input order.
    #[serde(default)]
    pub attributes: Vec<crate::io::Attribute>,
    /// The largest attribute values of the input's points (classes,
    /// return numbers, colour channels), found as it was read.
    #[serde(default)]
    pub maxima: Option<crate::io::AttributeMaxima>,
    /// A LAS/LAZ input's records and frame, kept for a LAS output written
    /// as the input came (`super::las_kept`).
    #[serde(default)]
    pub las: Option<super::las_kept::LasKept>,
    /// What the store keeps of its input in input order (absent in older
    /// stores: all of it).
    #[serde(default)]
    pub kept: Kept,
    /// With [`Kept::Nothing`]: the checksums `xyz.input` had before the
    /// build removed it (per `integrity::INPUT_SEGMENT` points), against
    /// which an export checks the input it reads again.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub input_sums: Vec<u32>,
    /// The input file the store was built from.
    pub source: String,
    /// Whether the input carried normals (kept in the normals column).
    pub source_has_normals: bool,
    /// Sampling density and noise, once a normals pass measured them.
    #[serde(default)]
    pub sampling: Option<super::sampling::SamplingStats>,
    /// For each derived column, what produced it, so a later pass asking
    /// for other parameters recomputes it rather than reusing it silently
    /// (absent: unknown, recomputed when asked). Stores of earlier versions
    /// kept a bare string under `provenance`; it is ignored, so their
    /// columns are recomputed once.
    #[serde(default, rename = "made_by")]
    pub provenance: std::collections::BTreeMap<String, super::columns::Provenance>,
    /// CRC-32 of each column file's segments (its tiles, or for an
    /// input-order column its runs of `integrity::INPUT_SEGMENT` points),
    /// by file name; checked when the store is opened.
    #[serde(default)]
    pub checksums: std::collections::BTreeMap<String, Vec<u32>>,
    /// Where the scanner stood for each run of points (an E57 file's scan
    /// poses), in input order; empty when the input does not say.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub stations: Vec<Station>,
    /// CRC-32 of this manifest's JSON without this field (set when saved).
    #[serde(default)]
    pub crc32: Option<u32>,
}

/// What a store keeps of its input, in input order, once it is built: what
/// an export of every point writes beside the computed columns (the exact
/// coordinates, the attributes, a LAS input's records), or what of it a
/// mesh may need.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Kept {
    /// The exact coordinates, the attributes and a LAS input's records: a
    /// store that serves exports without its input (`scanmesh tile`).
    #[default]
    All,
    /// The exact coordinates only: a run that writes no row per point (a
    /// mesh's vertices may be input points); the attributes are not listed.
    Coordinates,
    /// Nothing once built (the exact coordinates serve the build's passes
    /// and are removed, their checksums kept): an export reads the input
    /// again, each point checked against them (`super::reread`). The
    /// attributes and a LAS input's frame are listed as for [`Kept::All`].
    Nothing,
}

/// A run of points (by input index, as `index.u32` numbers them) that one
/// scanner position took.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
pub struct Station {
    /// Input index of the run's first point.
    pub first: u64,
    /// One past the input index of its last point.
    pub end: u64,
    /// The scanner's position (absolute coordinates).
    pub position: [f64; 3],
}

/// The coarse histogram grid the planner split; tile cores are integer boxes
/// of it, so they partition space exactly.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
pub struct GridSpec {
    /// Absolute position of grid corner (0,0,0).
    pub min: [f64; 3],
    /// Side of a grid cell (same units as the points).
    pub cell: f64,
    /// Cells along x, y and z.
    pub dims: [u32; 3],
}

/// One tile of the store: its points' range, core box and bounds.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct TileEntry {
    /// First store index of the tile's points; they run to `start + count`.
    pub start: u64,
    /// Points in the tile.
    pub count: u64,
    /// Core box in grid cells, half-open `[lo, hi)`.
    pub lo: [u32; 3],
    /// Upper corner (exclusive) of the core box, in grid cells.
    pub hi: [u32; 3],
    /// Tight bounds of the tile's stored points (relative to the origin).
    pub points_min: [f32; 3],
    /// Upper corner of the tile's stored points (relative to the origin).
    pub points_max: [f32; 3],
    /// First block (of `super::BLOCK` points) of this tile in the block table.
    pub first_block: u64,
}

/// The line `tile` closes with: what the store holds, and its spacing once
/// estimated.
impl std::fmt::Display for crate::summary::Summary<'_, Manifest> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let m = self.report;
        let spacing = match m.spacing {
            Some(s) => format!("{s:.4e}"),
            None => "not estimated".into(),
        };
        write!(
            f,
            "tile: {} points ({} skipped, {} duplicates), {} tiles, spacing {spacing}, {:.2} s, peak {} -> {}",
            m.count,
            m.skipped_invalid,
            m.duplicates,
            m.tiles.len(),
            self.secs,
            self.peak_text(),
            self.output.display()
        )
    }
}
