//! PCD input: files written by PCL's own tools (binary and
//! binary_compressed, in `fixtures/pcl/`, made with `pcl_ply2pcd -format 1`
//! and `pcl_convert_pcd_ascii_binary ... 2` from `sn.ply`) read back equal
//! to the PLY they came from; ASCII with fields the reader skips; and
//! malformed files are errors that name the file.

mod common;

use common::read_all;
use scanmesh::io::{open_reader, Format, InvalidPolicy, IoError, PointChunk};
use std::path::{Path, PathBuf};

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/pcl")
        .join(name)
}

#[test]
fn pcl_binary_and_compressed_files_equal_their_source() {
    let want = read_all(&fixture("sn.ply"), InvalidPolicy::Reject, 1000);
    assert_eq!(want.xyz.len(), 60);
    for name in ["snb.pcd", "snc.pcd"] {
        for max in [7, 1000] {
            let got = read_all(&fixture(name), InvalidPolicy::Reject, max);
            assert_eq!(got.xyz, want.xyz, "{name}");
            assert_eq!(got.normals, want.normals, "{name}");
            assert_eq!(got.indices, want.indices, "{name}");
        }
        let r = open_reader(&fixture(name), InvalidPolicy::Reject).unwrap();
        assert_eq!(r.info().format, Format::Pcd);
        assert_eq!(r.info().declared_count, Some(60));
    }
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    path
}

#[test]
fn ascii_with_other_fields_reads_x_y_z_and_normals() {
    let dir = tempfile::tempdir().unwrap();
    let text = "# .PCD v0.7\nVERSION 0.7\nFIELDS rgb x hist y z normal_x normal_y normal_z\n\
                SIZE 4 4 4 8 4 4 4 4\nTYPE U F F F F F F F\nCOUNT 1 1 3 1 1 1 1 1\n\
                WIDTH 2\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA ascii\n\
                7 1.5 0 0 0 2.25 -3 0 0 1\n9 4 1 2 3 5 6.5 1 0 0\n";
    let path = write(dir.path(), "a.pcd", text.as_bytes());
    let got = read_all(&path, InvalidPolicy::Reject, 10);
    let xyz: Vec<[f64; 3]> = got.xyz.iter().map(|p| p.to_array()).collect();
    assert_eq!(xyz, [[1.5, 2.25, -3.0], [4.0, 5.0, 6.5]]);
    let n: Vec<[f32; 3]> = got.normals.unwrap().iter().map(|n| n.to_array()).collect();
    assert_eq!(n, [[0.0, 0.0, 1.0], [1.0, 0.0, 0.0]]);
}

fn first_error(path: &Path, policy: InvalidPolicy) -> IoError {
    let mut r = match open_reader(path, policy) {
        Ok(r) => r,
        Err(e) => return e,
    };
    let mut chunk = PointChunk::default();
    loop {
        match r.read_chunk(&mut chunk, 1000) {
            Ok(0) => panic!("{}: read without an error", path.display()),
            Ok(_) => {}
            Err(e) => return e,
        }
    }
}

#[test]
fn malformed_files_are_errors_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let head = |points: &str, data: &str| {
        format!("FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nPOINTS {points}\nDATA {data}\n").into_bytes()
    };
    let mut short = head("3", "binary");
    short.extend_from_slice(&[0u8; 12 * 2 + 5]);
    let mut absurd = head("4000000000", "binary");
    absurd.extend_from_slice(&[0u8; 12]);
    let mut packed = head("2", "binary_compressed");
    packed.extend_from_slice(&[4, 0, 0, 0, 99, 0, 0, 0, 1, 2, 3, 4]);
    let mut nan = head("2", "ascii");
    nan.extend_from_slice(b"1 2 3\nnan 0 0\n");
    let cases: [(&str, Vec<u8>, &str); 6] = [
        ("short.pcd", short, "declares 3"),
        ("absurd.pcd", absurd, "declares 4000000000"),
        ("packed.pcd", packed, "99 bytes uncompressed"),
        ("nan.pcd", nan, "NaN"),
        (
            "noz.pcd",
            b"FIELDS x y\nSIZE 4 4\nTYPE F F\nPOINTS 1\nDATA ascii\n1 2\n".to_vec(),
            "no x, y and z",
        ),
        (
            "ragged.pcd",
            [head("2", "ascii"), b"1 2 3\n4 5\n".to_vec()].concat(),
            "line 7",
        ),
    ];
    for (name, bytes, want) in cases {
        let path = write(dir.path(), name, &bytes);
        let err = first_error(&path, InvalidPolicy::Reject).to_string();
        assert!(err.contains(name), "{name}: {err}");
        assert!(
            err.to_lowercase().contains(&want.to_lowercase()),
            "{name}: {err}"
        );
    }
    // Skipping drops the NaN point and keeps the input index of the rest.
    let got = read_all(&dir.path().join("nan.pcd"), InvalidPolicy::Skip, 10);
    assert_eq!(got.indices, [0]);
}
