//! `delaunay-time FILE [--check]`: the 3-D Delaunay triangulation of a point
//! file, timed alone (the peer of `tools/cgal_delaunay.cpp`): points read
//! whole, then `recon::delaunay::Delaunay::new` timed, cells and bytes per
//! point printed (structure capacity and the process's peak RSS).

use anyhow::{bail, Result};
use scanmesh::io::{open_reader, InvalidPolicy, PointChunk};
use scanmesh::recon::delaunay::{sanity_check, Delaunay, INFINITE};
use std::time::Instant;

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let Some(path) = args.get(1) else {
        bail!("usage: delaunay-time FILE [--check]");
    };
    let mut reader = open_reader(path.as_ref(), InvalidPolicy::Reject)?;
    let mut points = Vec::new();
    let mut chunk = PointChunk::default();
    while reader.read_chunk(&mut chunk, 1 << 20)? > 0 {
        points.extend_from_slice(&chunk.xyz);
    }
    let ranks: Vec<u64> = (0..points.len() as u64).collect();
    let rss0 = scanmesh::memory::peak_rss_bytes().unwrap_or(0);
    let t0 = Instant::now();
    let d = Delaunay::new(&points, &ranks)?;
    let secs = t0.elapsed().as_secs_f64();
    let rss1 = scanmesh::memory::peak_rss_bytes().unwrap_or(0);
    let finite = d
        .cell_slots()
        .iter()
        .filter(|c| !c.is_free() && !c.v.contains(&INFINITE))
        .count();
    let n = points.len() as f64;
    println!(
        "delaunay: {} points, {} vertices, {} finite cells, triangulation {:.3} s, structure {:.0} B/point, peak RSS growth {:.0} B/point (+24 B/point of input coordinates, +8 of ids)",
        points.len(),
        d.vertex_count(),
        finite,
        secs,
        d.heap_bytes() as f64 / n,
        rss1.saturating_sub(rss0) as f64 / n
    );
    if args.iter().any(|a| a == "--check") {
        let t = Instant::now();
        sanity_check(&d).map_err(anyhow::Error::msg)?;
        println!("sanity check passed in {:.2} s", t.elapsed().as_secs_f64());
    }
    Ok(())
}
