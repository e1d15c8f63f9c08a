//! A resumable run whose saved tile is arbitrary: the input's bytes become
//! the payload of tile 0 of the normals stage (or of the marching cubes,
//! when the first byte is odd), under a header whose length and checksum
//! are right, so the payload reaches the kernel's decoder and the seam that
//! consumes what it decodes. The run must end in a result or an error,
//! never a panic or an allocation sized by a decoded count.
#![no_main]

use glam::DVec3;
use libfuzzer_sys::fuzz_target;
use scanmesh::io::memory::MemoryReader;
use scanmesh::mesh::MeshFormat;
use scanmesh::normals::{compute_normals, NormalParams};
use scanmesh::pipeline::{NoProgress, RunOptions};
use scanmesh::store::{build_store, BuildOptions, Checkpoints, Job, TileTarget};
use scanmesh::{reconstruct_implicit, ImplicitParams};

/// A small sphere in four tiles (small: every input runs the whole stage).
fn points() -> Vec<DVec3> {
    scanmesh::synth::fibonacci::fibonacci_sphere(DVec3::ZERO, 1.0, 600)
}

/// A tile file as `store::checkpoint` writes it: magic, payload length,
/// CRC-32 of the payload, payload.
fn tile_file(payload: &[u8]) -> Vec<u8> {
    let mut f = b"SMTILE2\0".to_vec();
    f.extend((payload.len() as u64).to_le_bytes());
    f.extend(u64::from(crc32fast::hash(payload)).to_le_bytes());
    f.extend_from_slice(payload);
    f
}

fuzz_target!(|data: &[u8]| {
    let Some((&which, payload)) = data.split_first() else {
        return;
    };
    // In memory where there is one: every input runs a whole stage, and
    // its tile files and columns are forced to disk.
    let dir = match std::path::Path::new("/dev/shm").is_dir() {
        true => tempfile::tempdir_in("/dev/shm"),
        false => tempfile::tempdir(),
    }
    .expect("tempdir");
    let opts = BuildOptions {
        tiles: TileTarget::Points(150),
        ..BuildOptions::default()
    };
    let mut reader = MemoryReader::new("sphere", points(), None);
    let store_dir = dir.path().join("store");
    let mut store = build_store(&mut reader, &store_dir, &opts, &NoProgress).expect("store");
    let tiles = dir.path().join("tiles");
    let stage = if which & 1 == 0 { "normals" } else { "marching-cubes" };
    std::fs::create_dir_all(tiles.join(stage)).expect("stage dir");
    std::fs::write(tiles.join(stage).join("0000000.tile"), tile_file(payload)).expect("tile");
    store.keep_tiles(Checkpoints::new(&tiles, Job::Whole));
    let run = RunOptions::new(1);
    match which & 1 {
        0 => {
            let _ = compute_normals(&mut store, &NormalParams::default(), run, &NoProgress);
        }
        _ => {
            let out = dir.path().join("mesh.ply");
            let params = ImplicitParams::default();
            let format = MeshFormat::PlyBinary;
            let _ = reconstruct_implicit(&mut store, &params, &out, format, run, &NoProgress);
        }
    }
});
