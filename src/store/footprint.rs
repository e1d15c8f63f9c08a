//! What a run over an input takes on disk per point, known from the
//! input's header before a point is read (`run_footprint`): the store it
//! builds, the first term of its disk plan (the stages' own scratch comes
//! on top, [`crate::memory::plan::KernelCost`]), and its output's share.
//!
//! The columns: `xyz.f32` (12 B) and `index.u32` (4 B) in tile order, the
//! exact coordinates in input order (`xyz.input`: 24 B as f64, 12 B on a LAS
//! grid) unless the store keeps nothing of its input, the input's
//! attributes (intensity, colour, ...) and a LAS input's whole records
//! (`las.input`) when it keeps all, and the tile bounds (`blocks.f32`, 24 B
//! per 512 points).

use super::{is_store, Coordinates, Kept, PointStore, StoreError, BLOCK};
use crate::io::las_file::LasSource;
use crate::io::{open_reader, Format, ReadOptions, SourceInfo};
use crate::memory::KernelCost;
use std::path::Path;

/// Bytes per point of the tile-ordered columns every store has.
const TILE_COLUMNS: u64 = 12 + 4;

/// Disk bytes per point of the store an input of this description builds,
/// keeping what `kept` says of it ([`super::BuildOptions::keep`]). A store
/// that keeps nothing holds the exact coordinates while it is built, fewer
/// bytes than any stage's scratch after it, so its figure is the built
/// store's.
pub fn store_bytes_per_point(info: &SourceInfo, kept: Kept) -> Result<u64, StoreError> {
    let exact = match kept {
        Kept::Nothing => 0,
        _ => Coordinates::for_input(info.las_transform).item_bytes() as u64,
    };
    let whole = kept == Kept::All;
    let attributes = match whole {
        true => info.attributes.bytes_per_point() as u64,
        false => 0,
    };
    let records = match info.format {
        Format::Las | Format::Laz if whole => u64::from(LasSource::read(&info.path)?.record_len()),
        _ => 0,
    };
    Ok(TILE_COLUMNS + exact + attributes + records + 24u64.div_ceil(BLOCK))
}

/// A PLY row's x y z doubles, the part of a per-point command's declared
/// output figure ([`crate::memory::KernelCost::output_per_point`]) that is
/// the point itself; the rest are the command's columns.
const PLY_POSITION_BYTES: u64 = 24;

/// Output bytes per point of a per-point command whose declared figure
/// (a PLY row) is `declared`, writing `output` from this input. A LAS or
/// LAZ written from the same format carries the input's records as the
/// input stores them (compressed alike), so its bytes per point are the
/// input file's, plus the command's columns at most raw: the normals of
/// the 10M dragon wrote 20.6 B a point from a 10.4 B LAZ, planned 23.4.
/// Any other pair keeps the declared figure.
pub fn output_bytes_per_point(info: &SourceInfo, output: &Path, declared: u64) -> u64 {
    let same = matches!(
        (info.format, crate::io::format_from_name(output)),
        (Format::Las, Some((Format::Las, false))) | (Format::Laz, Some((Format::Laz, false)))
    );
    let input = std::fs::metadata(&info.path).map(|m| m.len());
    match (same, input, info.declared_count) {
        (true, Ok(bytes), Some(n)) if n > 0 && !info.gzip => {
            bytes.div_ceil(n) + declared.saturating_sub(PLY_POSITION_BYTES)
        }
        _ => declared,
    }
}

/// What a run over one input plans its disk from, known before it reads
/// a point: the run's check of its places (`pipeline::RunSettings`) and
/// `scanmesh info --plan` take it from here, so they plan alike.
#[derive(Clone, Copy, Debug)]
pub struct RunFootprint {
    /// Points the input declares (a store's count; `None` when a file's
    /// header gives none).
    pub points: Option<u64>,
    /// Bytes a point of the store the run builds takes (0 when the input
    /// is a store: it is there already).
    pub store_per_point: u64,
    /// The command's cost with the output's share by its format, and
    /// whether the export frees the store's positions.
    pub cost: KernelCost,
}

/// The footprint of a run of a command costing `cost` over `input`,
/// keeping `kept` of it in its store, writing `output` (`None`: the
/// command's declared PLY row). A store given as input is kept whole, so
/// its positions stay through the export; its format is not known here,
/// so the output keeps the declared figure. A file's header is read once.
pub fn run_footprint(
    input: &Path,
    read: ReadOptions,
    kept: Kept,
    output: Option<&Path>,
    cost: KernelCost,
) -> Result<RunFootprint, StoreError> {
    if is_store(input) {
        return Ok(RunFootprint {
            points: Some(PointStore::open_shared(input)?.len()),
            store_per_point: 0,
            cost: KernelCost {
                export_frees_positions: false,
                ..cost
            },
        });
    }
    let reader = open_reader(input, read)?;
    let info = reader.info();
    let declared = cost.output_per_point;
    Ok(RunFootprint {
        points: info.declared_count,
        store_per_point: store_bytes_per_point(info, kept)?,
        cost: KernelCost {
            output_per_point: output
                .map_or(declared, |o| output_bytes_per_point(info, o, declared)),
            ..cost
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::memory::MemoryReader;
    use crate::io::{open_reader, PointReader, ReadOptions};
    use crate::progress::NoProgress;
    use crate::store::{build_store, BuildOptions};
    use glam::DVec3;
    use std::path::Path;

    fn dir_bytes(dir: &Path) -> u64 {
        std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().metadata().unwrap().len())
            .sum()
    }

    /// The estimate is the store's size per point, to a few bytes of
    /// manifest and LAS frame, for generated points and for real LAS and
    /// LAZ files.
    #[test]
    fn the_estimate_is_the_built_stores_size() {
        let tmp = tempfile::tempdir().unwrap();
        let points: Vec<DVec3> = (0..20_000)
            .map(|i| DVec3::new((i % 141) as f64, (i / 141) as f64, (i % 7) as f64 * 0.1))
            .collect();
        let fixtures = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/las");
        let mut readers: Vec<Box<dyn PointReader>> =
            vec![Box::new(MemoryReader::new("cloud", points, None))];
        for name in ["autzen_trim_cut.laz", "32-1-472-150-76.laz", "autzen.las"] {
            readers.push(open_reader(&fixtures.join(name), ReadOptions::default()).unwrap());
        }
        for (i, mut reader) in readers.into_iter().enumerate() {
            // Each input built keeping one of the three.
            let keep = [Kept::All, Kept::Coordinates, Kept::Nothing][i % 3];
            let estimate = store_bytes_per_point(reader.info(), keep).unwrap();
            let name = reader.info().path.display().to_string();
            let dir = tmp.path().join(format!("{i}.store"));
            let opts = BuildOptions {
                keep,
                ..BuildOptions::default()
            };
            let store = build_store(reader.as_mut(), &dir, &opts, &NoProgress).unwrap();
            let per_point = dir_bytes(&dir) as f64 / store.len() as f64;
            let excess = per_point - estimate as f64;
            assert!(
                (-1.0..=1.0 + 8192.0 / store.len() as f64).contains(&excess),
                "{name} ({keep:?}): {per_point:.1} B a point built, {estimate} estimated"
            );
        }
    }
}
