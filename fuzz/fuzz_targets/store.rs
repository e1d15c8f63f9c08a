//! A whole store from arbitrary bytes: its manifest and every column file.
//! The manifest is always resealed (its checksum made right) so mutations
//! reach its fields; the columns' checksums are resealed when the first
//! byte is odd, so damaged columns reach the checks behind the checksums
//! (counts against sizes, ranges read, input indices), and when it is even
//! the checksums themselves must catch the damage. Opening the store,
//! reading every tile and exporting it must end in data or an error, never
//! a panic or an allocation sized by a damaged count.
#![no_main]

use libfuzzer_sys::fuzz_target;
use scanmesh::io::{Format, WriterSpec};
use scanmesh::pipeline::NoProgress;
use scanmesh::store::{export_points, integrity, PointStore};

/// The files a store holds besides its manifest, in the order the input's
/// bytes fill them.
const COLUMNS: [&str; 10] = [
    "xyz.f32",
    "index.u32",
    "blocks.f32",
    "xyz.input",
    "normal.f32",
    "flags.u8",
    "intensity.input",
    "gps_time.input",
    "classification.input",
    "return_number.input",
];

fuzz_target!(|data: &[u8]| {
    let Some((&flags, rest)) = data.split_first() else {
        return;
    };
    let Some((len, rest)) = rest.split_first_chunk::<2>() else {
        return;
    };
    let len = usize::from(u16::from_le_bytes(*len)).min(rest.len());
    let (manifest, mut columns) = rest.split_at(len);
    let dir = tempfile::tempdir().expect("tempdir");
    std::fs::write(dir.path().join("manifest.json"), manifest).expect("manifest");
    // Each column takes a length (u16) and that many bytes.
    for name in COLUMNS {
        let Some((n, tail)) = columns.split_first_chunk::<2>() else {
            break;
        };
        let n = usize::from(u16::from_le_bytes(*n)).min(tail.len());
        std::fs::write(dir.path().join(name), &tail[..n]).expect("column");
        columns = &tail[n..];
    }
    let _ = integrity::reseal(dir.path(), flags & 1 == 1);
    let Ok(store) = PointStore::open_shared(dir.path()) else {
        return;
    };
    let (mut xyz, mut ids, mut exact) = (Vec::new(), Vec::new(), Vec::new());
    for t in store.tiles() {
        let _ = store.read_coords(t.start, t.count, &mut xyz);
        let _ = store.read_indices(t.start, t.count, &mut ids);
    }
    let _ = store.read_exact(0, store.len(), &mut exact);
    let out = dir.path().join("out.ply");
    let spec = WriterSpec {
        with_normals: flags & 2 == 2,
        with_flags: flags & 4 == 4,
        attributes: store.attributes(),
        ..WriterSpec::new(Format::PlyBinaryLe)
    };
    // A small window: several windows, so the reordering runs too.
    let window = u64::from(flags >> 3).max(1) * 16;
    let _ = export_points(&store, &out, &spec, window, &NoProgress);
});
