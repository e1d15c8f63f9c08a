//! Every point reader on arbitrary bytes: the first byte picks the name the
//! file gets (the text formats are chosen by name; PLY, LAS and PCD by
//! content, which the rest of the bytes may or may not hold). Reading must
//! end in points or an error: no panic, no unbounded allocation, no hang.
#![no_main]

use libfuzzer_sys::fuzz_target;
use scanmesh::io::{open_reader, InvalidPolicy, PointChunk};

const NAMES: [&str; 6] = ["in.ply", "in.xyz", "in.csv", "in.las", "in.laz", "in.pcd"];

fuzz_target!(|data: &[u8]| {
    let Some((&pick, body)) = data.split_first() else {
        return;
    };
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join(NAMES[pick as usize % NAMES.len()]);
    std::fs::write(&path, body).expect("write");
    for policy in [InvalidPolicy::Reject, InvalidPolicy::Skip] {
        let Ok(mut reader) = open_reader(&path, policy) else {
            continue;
        };
        let mut chunk = PointChunk::default();
        // A chunk holds at most `max` points: the loop ends with the data.
        while let Ok(n) = reader.read_chunk(&mut chunk, 97) {
            assert!(n <= 97);
            if n == 0 {
                break;
            }
        }
    }
});
