//! A triangle mesh from a point file, through the library, in ten lines,
//! within a memory promise (256 MiB on 2 threads, as `--mem 256MiB`):
//! `cargo run --release --example reconstruct -- scan.ply mesh.ply`.
//! Without arguments it reconstructs 20,000 points of the embedded dragon.

use scanmesh::mesh::MeshFormat;
use scanmesh::recon::implicit::reconstruct::ImplicitReport;
use scanmesh::{build_store, reconstruct_implicit, ImplicitParams, MemoryBudget, PointReader};
use scanmesh::{open_stream_reader, NoProgress, Prepared, ReadOptions, RunSettings, Workspace};
use std::path::Path;

type Error = Box<dyn std::error::Error>;

fn main() -> Result<(), Error> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let output = args.get(1).map_or("mesh.ply", String::as_str);
    let report = match args.first() {
        Some(input) => reconstruct_file(input.as_ref(), output.as_ref())?,
        None => reconstruct(&mut *sample()?, output.as_ref())?,
    };
    println!(
        "{} vertices, {} triangles -> {output}",
        report.vertices, report.triangles
    );
    Ok(())
}

fn settings() -> RunSettings {
    RunSettings::new(MemoryBudget::new(256 << 20, 2))
}

/// The ten lines for a file: the output and scratch places and the disk
/// plan checked, a scratch store beside the output, the implicit mesh.
fn reconstruct_file(input: &Path, output: &Path) -> Result<ImplicitReport, Error> {
    let params = ImplicitParams::default();
    let (run, _) = settings().open(input, output, params.cost(), &NoProgress)?;
    mesh(run, &params, output)
}

/// The same for a stream: a store in a scratch directory, then the mesh.
fn reconstruct(reader: &mut dyn PointReader, output: &Path) -> Result<ImplicitReport, Error> {
    let work = tempfile::tempdir()?;
    let params = ImplicitParams::default();
    let build = settings().build_options(params.cost());
    let store = build_store(reader, &work.path().join("store"), &build, &NoProgress)?;
    let run = settings().prepare(Workspace::kept(store), params.cost())?;
    mesh(run, &params, output)
}

/// The implicit mesh of a prepared run.
fn mesh(
    mut run: Prepared,
    params: &ImplicitParams,
    output: &Path,
) -> Result<ImplicitReport, Error> {
    let (store, format) = (&mut run.ws.store, MeshFormat::PlyBinary);
    Ok(reconstruct_implicit(
        store,
        params,
        output,
        format,
        run.opts,
        &NoProgress,
    )?)
}

/// 20,000 noisy points of the embedded dragon, as an in-memory XYZ stream.
fn sample() -> Result<Box<dyn PointReader>, Error> {
    let (scan, _, _) = scanmesh::demo::dragon_scan(20_000, 0.1, 1)?;
    let text: String = scan
        .points
        .iter()
        .map(|p| format!("{} {} {}\n", p.x, p.y, p.z))
        .collect();
    let name = Path::new("dragon.xyz");
    Ok(open_stream_reader(
        name,
        std::io::Cursor::new(text),
        ReadOptions::default(),
    )?)
}

/// `cargo test` runs the example on the embedded sample, as a stream and
/// as a file: the same mesh.
#[test]
fn reconstructs_the_embedded_sample() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("mesh.ply");
    let report = reconstruct(&mut *sample().unwrap(), &out).unwrap();
    let (vertices, faces) = scanmesh::read_mesh_any(&out).unwrap();
    assert_eq!(vertices.len() as u64, report.vertices);
    assert_eq!(faces.len() as u64, report.triangles);
    assert!(faces.len() > 20_000, "{} triangles", faces.len());
    let xyz = dir.path().join("dragon.xyz");
    let (scan, _, _) = scanmesh::demo::dragon_scan(20_000, 0.1, 1).unwrap();
    let text: String = scan
        .points
        .iter()
        .map(|p| format!("{} {} {}\n", p.x, p.y, p.z))
        .collect();
    std::fs::write(&xyz, text).unwrap();
    let from_file = dir.path().join("file.ply");
    let again = reconstruct_file(&xyz, &from_file).unwrap();
    assert_eq!(again.triangles, report.triangles);
    assert!(std::fs::read(&from_file).unwrap() == std::fs::read(&out).unwrap());
}
