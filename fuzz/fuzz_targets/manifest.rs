//! A store whose manifest is arbitrary text beside small, valid columns:
//! opening it and reading every tile must end in data or an error, never a
//! panic or an allocation sized by the manifest's counts. The manifest is
//! resealed (its checksum, and its columns', made right for the bytes
//! there), so mutations reach the checks behind the checksums; that the
//! checksums catch damage is the `store` target's part.
#![no_main]

use libfuzzer_sys::fuzz_target;
use scanmesh::store::{integrity, PointStore};

fuzz_target!(|data: &[u8]| {
    let dir = tempfile::tempdir().expect("tempdir");
    // Columns of 60 points (xyz f32 x3, index u32, one block of bounds), as
    // in the seed manifest.
    std::fs::write(dir.path().join("xyz.f32"), vec![0u8; 720]).expect("xyz");
    std::fs::write(dir.path().join("index.u32"), vec![0u8; 240]).expect("index");
    std::fs::write(dir.path().join("blocks.f32"), vec![0u8; 24]).expect("blocks");
    std::fs::write(dir.path().join("xyz.input"), vec![0u8; 1440]).expect("exact");
    std::fs::write(dir.path().join("manifest.json"), data).expect("manifest");
    let _ = integrity::reseal(dir.path(), true);
    let Ok(store) = PointStore::open_shared(dir.path()) else {
        return;
    };
    let (mut xyz, mut ids) = (Vec::new(), Vec::new());
    for t in store.tiles() {
        let _ = store.read_coords(t.start, t.count, &mut xyz);
        let _ = store.read_indices(t.start, t.count, &mut ids);
    }
});
