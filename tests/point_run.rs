//! The library's per-point run (`rundir::PointRun`) is the command line's:
//! a library caller who opens a real scan through it, computes and writes
//! in input order gets the bytes `scanmesh normals` writes, the `--mem`
//! plan and what the CLI would print heard on the way.

use scanmesh::io::{not_held, ReadOptions, Returns, Selection};
use scanmesh::normals::{compute_normals, normals_output, NormalParams};
use scanmesh::pipeline::{MemoryBudget, NoProgress, RunSettings};
use scanmesh::rundir::{Hear, PointRun, Said};
use scanmesh::store::{export_points_keeping, PointStore, Rows};
use std::cell::RefCell;
use std::path::Path;

mod common;
use common::{fixture_arg, ok, scanmesh};

type Boxed = Box<dyn std::error::Error + Send + Sync>;

/// Keeps what the run says, in words.
#[derive(Default)]
struct Heard(RefCell<Vec<String>>);

impl Hear for Heard {
    fn hear(&self, said: Said<'_>) {
        let line = match said {
            Said::Reclaimed(files) => format!("reclaimed {}", files.len()),
            Said::Opened(store) => format!("opened {} points", store.len()),
            Said::Note(note) => note,
        };
        self.0.borrow_mut().push(line);
    }
}

/// Normals of `input` to `output` through the library, selecting `classes`.
fn library_normals(
    input: &Path,
    output: &Path,
    classes: Option<Vec<u8>>,
    keep: bool,
) -> Vec<String> {
    let read = ReadOptions {
        select: Selection {
            classes,
            returns: Returns::All,
        },
        ..ReadOptions::default()
    };
    let settings = RunSettings {
        budget: MemoryBudget::new(256 << 20, 2),
        tile_points: Some(4000),
        read,
        scratch_dir: None,
        scratch_limit: None,
        keep: scanmesh::store::Kept::Coordinates,
    };
    let heard = Heard::default();
    let run = PointRun {
        settings: &settings,
        session: None,
        keep_unselected: keep,
        progress: &NoProgress,
        hear: &heard,
    };
    let params = NormalParams::default();
    let mut spec = normals_output(output, false).expect("a PLY holds normals");
    // Any error type the run's own convert into: a boxed one here.
    let compute = |store: &mut PointStore, c: scanmesh::rundir::Computing| -> Result<_, Boxed> {
        Ok(compute_normals(store, &params, c.opts, c.progress)?)
    };
    let write = |store: &PointStore, to: &Rows, hear: &dyn Hear| -> Result<u64, Boxed> {
        if let Some(note) = not_held(to.output, spec.carry(store.attributes())) {
            hear.hear(Said::Note(note));
        }
        Ok(export_points_keeping(store, &spec, to)?)
    };
    let (report, rows) = run
        .run((input, output), params.cost(), compute, write)
        .expect("the library's run");
    assert!(
        rows >= report.points,
        "{rows} rows for {} points",
        report.points
    );
    heard.0.into_inner()
}

#[test]
fn the_library_run_writes_the_bytes_the_command_line_writes() {
    let dir = tempfile::tempdir().expect("tmp");
    // (input, output extension, classes selected, unselected kept)
    let cases: [(&str, &str, Option<Vec<u8>>, bool); 4] = [
        ("las/autzen_trim_cut.laz", "ply", None, false),
        ("las/autzen_trim_cut.laz", "ply", Some(vec![2]), true),
        ("las/autzen_trim_cut.laz", "xyz", None, false),
        ("e57/three_scans.e57", "ply", None, false),
    ];
    for (k, (fixture, ext, classes, keep)) in cases.into_iter().enumerate() {
        let input = fixture_arg(fixture);
        let lib_out = dir.path().join(format!("lib{k}.{ext}"));
        let cli_out = dir.path().join(format!("cli{k}.{ext}"));
        let heard = library_normals(Path::new(&input), &lib_out, classes.clone(), keep);
        let mut args = vec!["normals", &input, "-o", cli_out.to_str().unwrap(), "-q"];
        let class_arg = classes.map(|c| c.iter().map(u8::to_string).collect::<Vec<_>>().join(","));
        if let Some(c) = &class_arg {
            args.extend(["--classes", c]);
        }
        if keep {
            args.extend(["--unselected", "keep"]);
        }
        args.extend(["--mem", "256MiB", "--threads", "2", "--tile-points", "4000"]);
        ok(scanmesh(&args));
        let (lib, cli) = (
            std::fs::read(&lib_out).unwrap(),
            std::fs::read(&cli_out).unwrap(),
        );
        assert!(
            lib == cli,
            "{fixture}: the library's output differs from the CLI's"
        );
        assert!(
            heard.iter().any(|l| l.starts_with("opened ")),
            "{fixture}: {heard:?}"
        );
        // XYZ text cannot hold a LAS input's attributes: said, as the CLI
        // says it; a PLY holds them.
        let said = heard.iter().any(|l| l.contains("cannot hold"));
        assert_eq!(said, ext == "xyz", "{fixture} to .{ext}: {heard:?}");
    }
}
