//! A triangle mesh from a point file, through the library, in ten lines:
//! `cargo run --release --example reconstruct -- scan.ply mesh.ply`.
//! Without arguments it reconstructs 20,000 points of the embedded dragon.

use scanmesh::mesh::MeshFormat;
use scanmesh::recon::implicit::reconstruct::ImplicitReport;
use scanmesh::{build_store, reconstruct_implicit, BuildOptions, ImplicitParams, PointReader};
use scanmesh::{open_reader, open_stream_reader, NoProgress, ReadOptions, RunOptions};
use std::path::Path;

type Error = Box<dyn std::error::Error>;

fn main() -> Result<(), Error> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut reader = match args.first() {
        Some(input) => open_reader(input.as_ref(), ReadOptions::default())?,
        None => sample()?,
    };
    let output = args.get(1).map_or("mesh.ply", String::as_str);
    let report = reconstruct(&mut *reader, output.as_ref())?;
    println!(
        "{} vertices, {} triangles -> {output}",
        report.vertices, report.triangles
    );
    Ok(())
}

/// The ten lines: a store in a scratch directory, then the implicit mesh.
fn reconstruct(reader: &mut dyn PointReader, output: &Path) -> Result<ImplicitReport, Error> {
    let work = tempfile::tempdir()?;
    let options = BuildOptions::default();
    let mut store = build_store(reader, &work.path().join("store"), &options, &NoProgress)?;
    let (params, threads) = (ImplicitParams::default(), RunOptions::new(2));
    let format = MeshFormat::PlyBinary;
    Ok(reconstruct_implicit(
        &mut store,
        &params,
        output,
        format,
        threads,
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

/// `cargo test` runs the example on the embedded sample.
#[test]
fn reconstructs_the_embedded_sample() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("mesh.ply");
    let report = reconstruct(&mut *sample().unwrap(), &out).unwrap();
    let (vertices, faces) = scanmesh::read_mesh_any(&out).unwrap();
    assert_eq!(vertices.len() as u64, report.vertices);
    assert_eq!(faces.len() as u64, report.triangles);
    assert!(faces.len() > 20_000, "{} triangles", faces.len());
}
