//! Shared helpers of the integration tests: run the library's whole data
//! flow (ingest -> store -> tiles -> kernel -> export) on generated points.
#![allow(dead_code)]

use glam::{DVec3, Vec3};
use scanmesh::io::memory::MemoryReader;
use scanmesh::io::{open_reader, Format, InvalidPolicy, PointChunk, WriterSpec};
use scanmesh::normals::{compute_normals, NormalParams, NormalsReport};
use scanmesh::pipeline::{NoProgress, RunOptions};
use scanmesh::store::{build_store, export_points, BuildOptions, PointStore, TileTarget};
use std::path::Path;
use std::process::{Command, Output};

/// Builds a store of `points` in `dir` with tiles of at most `tile_points`.
pub fn store_of(points: &[DVec3], dir: &Path, tile_points: u64) -> PointStore {
    let mut reader = MemoryReader::new("generated", points.to_vec(), None);
    let opts = BuildOptions {
        tiles: TileTarget::Points(tile_points),
        ..BuildOptions::default()
    };
    build_store(&mut reader, dir, &opts, &NoProgress).expect("build store")
}

/// Per-point results read back from an exported PLY, in input order.
pub struct NormalsOut {
    pub report: NormalsReport,
    pub normals: Vec<Vec3>,
    pub flags: Vec<u8>,
    pub bytes: Vec<u8>,
}

/// Runs `f` on a fresh store of `points` (tiles of at most `tile_points`)
/// inside a rayon pool of `threads`, with a scratch directory for outputs.
pub fn with_store<R: Send>(
    points: &[DVec3],
    tile_points: u64,
    threads: usize,
    f: impl FnOnce(&mut PointStore, &Path) -> R + Send,
) -> R {
    let dir = tempfile::tempdir().expect("tempdir");
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("pool");
    pool.install(|| {
        let mut store = store_of(points, &dir.path().join("store"), tile_points);
        f(&mut store, dir.path())
    })
}

/// Runs normals through the whole pipeline with `threads` workers (and a
/// rayon pool of that size), exporting a binary PLY and reading it back.
pub fn normals_of(
    points: &[DVec3],
    tile_points: u64,
    threads: usize,
    params: &NormalParams,
) -> NormalsOut {
    normals_with(points, tile_points, RunOptions::new(threads), params)
}

/// [`normals_of`] with the run options given (e.g. a memory promise that
/// sends global passes down their external path).
pub fn normals_with(
    points: &[DVec3],
    tile_points: u64,
    opts: RunOptions,
    params: &NormalParams,
) -> NormalsOut {
    with_store(points, tile_points, opts.threads, |store, dir| {
        let report = compute_normals(store, params, opts, &NoProgress).expect("normals");
        let out = dir.join("out.ply");
        let spec = WriterSpec {
            with_normals: true,
            with_flags: true,
            ..WriterSpec::new(Format::PlyBinaryLe)
        };
        export_points(store, &out, &spec, 7777, &NoProgress).expect("export");
        let (normals, flags) = read_normals(&out);
        NormalsOut {
            report,
            normals,
            flags,
            bytes: std::fs::read(&out).expect("read output"),
        }
    })
}

/// Normals of a PLY file in file order; flags are parsed from the raw
/// records (the point reader does not carry them).
pub fn read_normals(path: &Path) -> (Vec<Vec3>, Vec<u8>) {
    let mut r = open_reader(path, InvalidPolicy::Reject).expect("open");
    let mut chunk = PointChunk::default();
    let mut normals = Vec::new();
    while r.read_chunk(&mut chunk, 4096).expect("read") > 0 {
        normals.extend(chunk.normals.as_ref().expect("normals present"));
    }
    let bytes = std::fs::read(path).expect("read");
    let body = bytes
        .windows(11)
        .position(|w| w == b"end_header\n")
        .map(|p| p + 11)
        .expect("header end");
    // Records: 3 doubles, 3 floats, 1 flag byte.
    let flags = bytes[body..].chunks_exact(37).map(|r| r[36]).collect();
    (normals, flags)
}

/// Angle in degrees between two directions, ignoring sign when `unsigned`.
pub fn angle_deg(a: DVec3, b: DVec3, unsigned: bool) -> f64 {
    let mut c = a.normalize().dot(b.normalize());
    if unsigned {
        c = c.abs();
    }
    c.clamp(-1.0, 1.0).acos().to_degrees()
}

pub fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    v[v.len() / 2]
}

/// Every point of a file, read back in chunks.
pub struct ReadBack {
    pub xyz: Vec<DVec3>,
    pub normals: Option<Vec<Vec3>>,
    pub indices: Vec<u64>,
    pub chunks: usize,
}

/// Reads every point with chunks of at most `max`, checking the chunk
/// contract (size bound, index bookkeeping) on the way.
pub fn read_all(path: &Path, policy: InvalidPolicy, max: usize) -> ReadBack {
    let mut r = open_reader(path, policy).unwrap();
    let mut out = ReadBack {
        xyz: Vec::new(),
        normals: r.info().has_normals.then(Vec::new),
        indices: Vec::new(),
        chunks: 0,
    };
    let mut chunk = PointChunk::default();
    loop {
        let n = r.read_chunk(&mut chunk, max).unwrap();
        assert_eq!(n, chunk.len());
        assert!(n <= max.max(1), "chunk of {n} > max {max}");
        if n == 0 {
            break;
        }
        out.chunks += 1;
        assert_eq!(
            chunk.index_of(0),
            chunk.first_index,
            "first_index is xyz[0]'s"
        );
        out.indices.extend((0..n).map(|i| chunk.index_of(i)));
        out.xyz.extend_from_slice(&chunk.xyz);
        match (&mut out.normals, &chunk.normals) {
            (Some(all), Some(n)) => all.extend_from_slice(n),
            (None, None) => {}
            _ => panic!("normals present in some chunks only"),
        }
    }
    assert_eq!(r.read_chunk(&mut chunk, max).unwrap(), 0, "stays exhausted");
    out
}

/// Runs the `scanmesh` binary with `args`.
pub fn scanmesh(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_scanmesh"))
        .args(args)
        .output()
        .expect("run scanmesh")
}

/// The standard output of a run that must have succeeded.
pub fn ok(out: Output) -> String {
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "failed: {err}");
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// The path of `rel` under `tests/fixtures`, as a command-line argument.
pub fn fixture_arg(rel: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(rel)
        .display()
        .to_string()
}

/// Runs `scanmesh reconstruct` on fixture `rel` into `out` with `args`
/// after it, and returns what it said; fails the test, naming the
/// fixture, when the run fails.
pub fn reconstruct_fixture(rel: &str, out: &Path, args: &[&str]) -> String {
    let (input, o) = (fixture_arg(rel), out.display().to_string());
    let run = scanmesh(&[&["reconstruct", input.as_str(), "-o", o.as_str()][..], args].concat());
    assert!(
        run.status.success(),
        "{rel}: {}",
        String::from_utf8_lossy(&run.stderr)
    );
    String::from_utf8_lossy(&run.stdout).into_owned()
}
