//! A store that keeps nothing of its input (`Kept::Nothing`, what a
//! per-point run builds) has its export read the input again: the output
//! is byte for byte the one a store keeping the whole input writes, on real
//! LAS, LAZ, E57 and PCD scans, with a selection, with the unselected
//! points kept and with invalid records skipped; and an input changed,
//! replaced or cut between the build and the export fails the export,
//! naming the file, with no output left behind.

use glam::DVec3;
use scanmesh::io::{open_reader, InvalidPolicy, ReadOptions, Returns, Selection};
use scanmesh::normals::{compute_normals, normals_output, NormalParams};
use scanmesh::pipeline::{NoProgress, RunOptions};
use scanmesh::store::{
    build_store, export_points_keeping, BuildOptions, Kept, PointStore, Rows, StoreError,
    TileTarget,
};
use std::path::Path;

mod common;
use common::fixture_arg;

/// A store of `input` read as `read`, keeping `keep`, with normals.
fn store_with_normals(input: &Path, read: &ReadOptions, keep: Kept, dir: &Path) -> PointStore {
    let mut reader = open_reader(input, read.clone()).expect("open the input");
    let opts = BuildOptions {
        tiles: TileTarget::Points(3000),
        keep,
        ..BuildOptions::default()
    };
    let mut store = build_store(reader.as_mut(), dir, &opts, &NoProgress).expect("build");
    compute_normals(
        &mut store,
        &NormalParams::default(),
        RunOptions::new(2),
        &NoProgress,
    )
    .expect("normals");
    store
}

/// Exports `store` (built from `input` read as `read`) to `output` in
/// windows of 1,500 points.
fn export(
    store: &PointStore,
    input: &Path,
    read: &ReadOptions,
    output: &Path,
    keep_unselected: bool,
) -> Result<u64, StoreError> {
    let mut spec = normals_output(output, false).expect("a format that holds normals");
    spec.carry(store.attributes());
    let rows = Rows {
        output,
        window: 1500,
        input: Some((input, read)),
        keep_unselected,
        progress: &NoProgress,
    };
    export_points_keeping(store, &spec, &rows)
}

/// An ASCII PLY of a tilted plane with every 97th point NaN.
fn plane_with_nans(path: &Path) -> u64 {
    let n = 4000;
    let mut text = format!(
        "ply\nformat ascii 1.0\nelement vertex {n}\nproperty double x\nproperty double y\nproperty double z\nend_header\n"
    );
    for i in 0..n {
        let p = DVec3::new((i % 63) as f64 * 0.1, (i / 63) as f64 * 0.1, 0.0);
        match i % 97 {
            5 => text.push_str("nan 0 0\n"),
            _ => text.push_str(&format!("{} {} {}\n", p.x, p.y, 0.3 * p.x + 1e5)),
        }
    }
    std::fs::write(path, text).expect("write the PLY");
    n
}

#[test]
fn reading_the_input_again_writes_the_bytes_of_the_kept_copy() {
    let dir = tempfile::tempdir().expect("tmp");
    let nans = dir.path().join("nans.ply");
    plane_with_nans(&nans);
    let class_2 = ReadOptions {
        select: Selection {
            classes: Some(vec![2]),
            returns: Returns::All,
        },
        ..ReadOptions::default()
    };
    let skip = ReadOptions::from(InvalidPolicy::Skip);
    let every = ReadOptions::default();
    // (input, output extension, read, unselected kept)
    let cases: [(String, &str, &ReadOptions, bool); 7] = [
        (fixture_arg("las/autzen_trim_cut.laz"), "laz", &every, false),
        (
            fixture_arg("las/autzen_trim_cut.laz"),
            "ply",
            &class_2,
            true,
        ),
        (fixture_arg("las/autzen.las"), "las", &class_2, false),
        (fixture_arg("las/extrabytes.las"), "las", &every, false),
        (fixture_arg("e57/three_scans.e57"), "ply", &every, false),
        (fixture_arg("pcd/organised_milk.pcd"), "pcd", &every, false),
        (nans.display().to_string(), "xyz", &skip, false),
    ];
    for (k, (input, ext, read, keep)) in cases.iter().enumerate() {
        let input = Path::new(input);
        let mut bytes = Vec::new();
        for kept in [Kept::All, Kept::Nothing] {
            let store_dir = dir.path().join(format!("s{k}{kept:?}"));
            let store = store_with_normals(input, read, kept, &store_dir);
            if kept == Kept::Nothing {
                let left: Vec<String> = std::fs::read_dir(&store_dir)
                    .unwrap()
                    .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
                    .filter(|name| name.ends_with(".input"))
                    .collect();
                assert!(left.is_empty(), "{input:?}: the store kept {left:?}");
            }
            let out = dir.path().join(format!("o{k}{kept:?}.{ext}"));
            let rows = export(&store, input, read, &out, *keep).expect("export");
            assert!(rows >= store.len(), "{input:?}: {rows} rows");
            bytes.push(std::fs::read(&out).unwrap());
        }
        assert!(
            bytes[0] == bytes[1],
            "{input:?} to {ext}: reading the input again wrote other bytes"
        );
    }
}

/// Reads a LAS header's offset to the points and record length.
fn las_layout(bytes: &[u8]) -> (usize, usize) {
    let offset = u32::from_le_bytes(bytes[96..100].try_into().unwrap()) as usize;
    let len = u16::from_le_bytes(bytes[105..107].try_into().unwrap()) as usize;
    (offset, len)
}

/// The export of a store of `input` after `change` is made to the file
/// fails and leaves no output; returns the error.
fn export_after(input: &Path, change: impl FnOnce(&Path)) -> StoreError {
    let dir = tempfile::tempdir().expect("tmp");
    let copy = dir.path().join(input.file_name().unwrap());
    std::fs::copy(input, &copy).expect("copy the input");
    let read = ReadOptions::default();
    let store = store_with_normals(&copy, &read, Kept::Nothing, &dir.path().join("s"));
    change(&copy);
    let out = dir.path().join("out.las");
    let err = export(&store, &copy, &read, &out, false).expect_err("a changed input");
    let left: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .filter(|n| n.to_string_lossy().contains("out"))
        .collect();
    assert!(
        left.is_empty(),
        "{input:?}: the failed export left {left:?}"
    );
    assert!(
        err.to_string().contains(&copy.display().to_string()),
        "the error names the input: {err}"
    );
    err
}

#[test]
fn an_input_changed_since_the_build_fails_the_export() {
    let las = Path::new(&fixture_arg("las/autzen.las")).to_path_buf();
    // One point's x moved by one integer step.
    let err = export_after(&las, |path| {
        let mut bytes = std::fs::read(path).unwrap();
        let (offset, len) = las_layout(&bytes);
        bytes[offset + 7 * len] ^= 1;
        std::fs::write(path, bytes).unwrap();
    });
    assert!(
        matches!(err, StoreError::InputChanged { .. }),
        "a moved point: {err}"
    );
    // Two points swapped: the same points, in another order.
    let err = export_after(&las, |path| {
        let mut bytes = std::fs::read(path).unwrap();
        let (offset, len) = las_layout(&bytes);
        let (a, b) = (offset + 3 * len, offset + 4 * len);
        for i in 0..12 {
            bytes.swap(a + i, b + i);
        }
        std::fs::write(path, bytes).unwrap();
    });
    assert!(
        matches!(err, StoreError::InputChanged { .. }),
        "swapped points: {err}"
    );
    // Replaced by another scan.
    let other = fixture_arg("las/autzen_trim_cut.laz");
    let laz = Path::new(&fixture_arg("las/32-1-472-150-76.laz")).to_path_buf();
    let err = export_after(&laz, |path| {
        std::fs::copy(&other, path).unwrap();
    });
    assert!(
        matches!(err, StoreError::InputChanged { .. }),
        "another scan: {err}"
    );
    // Points appended to a text file, then a line cut off another.
    let dir = tempfile::tempdir().expect("tmp");
    let ply = dir.path().join("plane.xyz");
    let text: String = (0..3000)
        .map(|i| format!("{} {} {}\n", i % 50, i / 50, (i % 7) as f64 * 0.01))
        .collect();
    std::fs::write(&ply, &text).unwrap();
    let err = export_after(&ply, |path| {
        std::fs::write(path, format!("{text}1 2 3\n")).unwrap();
    });
    assert!(matches!(err, StoreError::InputChanged { .. }), "{err}");
    let err = export_after(&ply, |path| {
        let cut = &text[..text.len() - 8];
        std::fs::write(path, &cut[..cut.rfind('\n').unwrap() + 1]).unwrap();
    });
    assert!(matches!(err, StoreError::InputChanged { .. }), "{err}");
}
