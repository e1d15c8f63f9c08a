//! The E57 reader on arbitrary content. Every 1 KiB page of an E57 ends in
//! a CRC-32C of the page, so arbitrary bytes would almost all stop at the
//! first checksum: the fuzzer's bytes are the pages' payloads (1020 bytes
//! each), and the target writes each page with its checksum, so mutations
//! reach the header, the XML section and the packet decoder. The first
//! byte picks the scan selection and the invalid-point policy. Reading
//! must end in points or an error: no panic, no unbounded allocation, no
//! hang. Seed: `seeds/e57/three_scans` (`tests/io_e57.rs` writes the same
//! kind of file; the seed is `tests/fixtures/e57/three_scans.e57` with the
//! checksums taken out).
#![no_main]

use libfuzzer_sys::fuzz_target;
use scanmesh::io::e57::list_scans;
use scanmesh::io::{open_reader, InvalidPolicy, PointChunk, ReadOptions};

const PAGE: usize = 1024;
const PAYLOAD: usize = PAGE - 4;

fn crc32c(data: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &b in data {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 == 1 {
                (crc >> 1) ^ 0x82F6_3B78
            } else {
                crc >> 1
            };
        }
    }
    !crc
}

/// Payloads -> pages, each with its big-endian checksum.
fn paged(logical: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(logical.len() / PAYLOAD * PAGE + PAGE);
    for part in logical.chunks(PAYLOAD) {
        let mut page = [0u8; PAYLOAD];
        page[..part.len()].copy_from_slice(part);
        out.extend_from_slice(&page);
        out.extend_from_slice(&crc32c(&page).to_be_bytes());
    }
    out
}

fuzz_target!(|data: &[u8]| {
    let Some((&pick, body)) = data.split_first() else {
        return;
    };
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("in.e57");
    std::fs::write(&path, paged(body)).expect("write");
    let _ = list_scans(&path);
    let policy = match pick & 1 {
        0 => InvalidPolicy::Reject,
        _ => InvalidPolicy::Skip,
    };
    let scans = match (pick >> 1) % 4 {
        0 => None,
        1 => Some(vec![0]),
        2 => Some(vec![2, 0]),
        _ => Some(vec![usize::from(pick >> 3)]),
    };
    let Ok(mut reader) = open_reader(&path, ReadOptions { policy, scans, select: Default::default() }) else {
        return;
    };
    let mut chunk = PointChunk::default();
    // A chunk holds at most `max` points: the loop ends with the data.
    while let Ok(n) = reader.read_chunk(&mut chunk, 97) {
        assert!(n <= 97);
        if n == 0 {
            break;
        }
        assert!(chunk.xyz.iter().all(|p| p.is_finite()));
    }
});
