//! `features-eval`: feature lines against true ones, per kind: recall (the
//! share of true length within the tolerance of an extracted line) and
//! precision (the share of extracted length within the tolerance of a true
//! line), sampled every quarter of the tolerance (the protocol:
//! 1 sp, every 0.25 sp).
//!
//! `scangen stepped-block -n 100000 --noise-spacing 0.1 -o b.ply --truth t.ply`
//! `scanmesh features b.ply -o lines.ply`
//! `features-eval lines.ply --truth t.ply --points b.ply`

use anyhow::{bail, Context, Result};
use clap::Parser;
use scanmesh::features::lines::LineGraph;
use scanmesh::features::score::score;
use scanmesh::io::{open_reader, InvalidPolicy, PointChunk};
use scanmesh::synth::TrueSegment;
use std::path::{Path, PathBuf};

#[derive(Parser)]
#[command(
    name = "features-eval",
    about = "Feature lines against true lines: recall and precision per kind"
)]
struct Args {
    /// Extracted lines (`scanmesh features` PLY).
    lines: PathBuf,
    /// True lines (`scangen --truth` PLY).
    #[arg(long)]
    truth: PathBuf,
    /// The input points, to measure sp (their mean nearest-neighbour distance).
    #[arg(long)]
    points: Option<PathBuf>,
    /// sp given directly (instead of --points).
    #[arg(long)]
    sp: Option<f64>,
    /// Tolerance in sp.
    #[arg(long, default_value_t = 1.0)]
    tolerance: f64,
    #[arg(long)]
    json: bool,
    /// Also print where the missed length lies: missed true length by its
    /// distance to the end of its true segment and to the nearest line
    /// found, and the unmatched found length by its distance to the truth.
    #[arg(long)]
    breakdown: bool,
}

fn main() -> Result<()> {
    let a = Args::parse();
    let sp = match (a.sp, &a.points) {
        (Some(sp), _) => sp,
        (None, Some(p)) => mean_nn(p)?,
        (None, None) => bail!("give --points or --sp"),
    };
    let found = LineGraph::read(&a.lines)?;
    let truth = LineGraph::read(&a.truth)?;
    let segs: Vec<TrueSegment> = truth
        .edges
        .iter()
        .map(|&(x, y, kind)| TrueSegment {
            kind,
            a: truth.vertices[x as usize],
            b: truth.vertices[y as usize],
        })
        .collect();
    let tol = a.tolerance * sp;
    let scores = score(&found, &segs, tol, tol / 4.0);
    let pct = |v: Option<f64>| v.map_or("n/a".to_string(), |v| format!("{:.2} %", 100.0 * v));
    if a.json {
        let kind = |s: &scanmesh::features::score::KindScore| {
            serde_json::json!({"recall": s.recall, "precision": s.precision,
                "true_length_sp": s.true_length / sp, "found_length_sp": s.found_length / sp})
        };
        let j = serde_json::json!({"sp": sp, "tolerance_sp": a.tolerance,
            "ridge": kind(&scores[0]), "valley": kind(&scores[1])});
        println!("{}", serde_json::to_string_pretty(&j)?);
    } else {
        for (name, s) in ["ridge", "valley"].iter().zip(&scores) {
            println!(
                "{name}: recall {} precision {} (true length {:.1} sp, found {:.1} sp; tolerance {} sp, sp {:.4e})",
                pct(s.recall),
                pct(s.precision),
                s.true_length / sp,
                s.found_length / sp,
                a.tolerance,
                sp
            );
        }
    }
    if a.breakdown {
        print_breakdown(&found, &truth, tol, sp);
    }
    Ok(())
}

fn print_breakdown(found: &LineGraph, truth: &LineGraph, tol: f64, sp: f64) {
    use scanmesh::features::score::{kind_segments, misses, Misses, END_BUCKETS};
    use scanmesh::synth::LineKind;
    let step = tol / 4.0;
    let len = |m: &Misses, e: usize, n: usize| m.counts[e][n] as f64 * step / sp;
    for (name, kind, other) in [
        ("ridge", LineKind::Ridge, LineKind::Valley),
        ("valley", LineKind::Valley, LineKind::Ridge),
    ] {
        let (t, f) = (kind_segments(truth, kind), kind_segments(found, kind));
        let (tw, fw) = (kind_segments(truth, other), kind_segments(found, other));
        for (side, m) in [
            ("missed true", misses(&t, &f, &fw, tol, step)),
            ("unmatched found", misses(&f, &t, &tw, tol, step)),
        ] {
            let total = m.samples as f64 * step / sp;
            println!(
                "{name} {side} length (sp; of {total:.1}), rows: distance to own segment end < {END_BUCKETS:?} tol / beyond; columns: nearest other side <= 2, <= 4, > 4 tol; {:.1} sp within tol of the other kind",
                m.other_kind as f64 * step / sp
            );
            for e in 0..5 {
                println!(
                    "  {:>6.1} {:>6.1} {:>6.1}",
                    len(&m, e, 0),
                    len(&m, e, 1),
                    len(&m, e, 2)
                );
            }
        }
    }
}

/// Exact mean nearest-neighbour distance of a point file.
fn mean_nn(path: &Path) -> Result<f64> {
    let mut r = open_reader(path, InvalidPolicy::Reject)
        .with_context(|| format!("reading {}", path.display()))?;
    let mut chunk = PointChunk::default();
    let mut pts = Vec::new();
    while r.read_chunk(&mut chunk, 1 << 16)? > 0 {
        pts.extend_from_slice(&chunk.xyz);
    }
    scanmesh::mesh::distance::mean_spacing(&pts).context("fewer than two points")
}
