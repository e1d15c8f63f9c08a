//! `--report FILE.json`: what a run did and what it cost, for the morning
//! after an overnight run and for regression benches. Every stage a
//! command reports through [`Progress`] is timed here (wall, CPU, peak RSS,
//! storage bytes), whatever the terminal shows; the command's summary line
//! and its outcome (or error) close the report. The file appears whole or
//! not at all (written beside, then renamed).
//!
//! Input records a reader dropped (`--skip-invalid`, or records the file
//! marks invalid) are told in the summary line and the report
//! (`skipped_invalid`) whatever the command, so nobody joins an output to
//! its input by position unwarned: a command names its input's count once
//! it is known ([`input_skipped`]).

use super::clock::{Mark, Span};
use scanmesh::io::LeftOut;
use scanmesh::mesh::{MeshAudit, MeshError};
use scanmesh::pipeline::Progress;
use serde::Serialize;
use std::io::Write;
use std::path::Path;
use std::sync::Mutex;

/// Stages and summary of this process's run.
static LOG: Mutex<Log> = Mutex::new(Log {
    stages: Vec::new(),
    summary: None,
    skipped: None,
    left_out: None,
    kept: false,
    audit: None,
});

struct Log {
    stages: Vec<Stage>,
    summary: Option<String>,
    /// The input read and the records dropped from it.
    skipped: Option<(String, u64)>,
    /// Records of the input left out: no return, or not selected.
    left_out: Option<LeftOut>,
    /// Whether the output holds the unselected points, flagged.
    kept: bool,
    /// The audit of the mesh the run wrote (complete or not).
    audit: Option<MeshAudit>,
}

#[derive(Clone, Serialize)]
struct Stage {
    name: String,
    #[serde(flatten)]
    span: Span,
}

#[derive(Serialize)]
struct Report<'a> {
    scanmesh_version: &'a str,
    /// The command line, as given.
    args: Vec<String>,
    /// "ok", or the error and its causes.
    outcome: String,
    summary: Option<String>,
    /// Input records dropped (non-finite coordinates or a cut last line
    /// under --skip-invalid, or marked invalid by the file); `None` when
    /// the command read no input.
    skipped_invalid: Option<u64>,
    /// Input records not processed: pixels of an organised cloud without
    /// a return (NaN), points --classes / --returns did not select.
    left_out: Option<LeftOut>,
    /// What the mesh written is (`reconstruct`): its boundary, non-manifold
    /// and inconsistently wound edges, non-manifold vertices, components,
    /// closed ones and their volumes; also when it broke the run's promise
    /// and was written as `NAME.incomplete.EXT`.
    mesh_audit: Option<MeshAudit>,
    total: Span,
    stages: Vec<Stage>,
}

/// Times the stages `inner` shows.
pub struct Recorder {
    inner: Box<dyn Progress>,
    open: Mutex<Option<(String, Mark)>>,
}

impl Recorder {
    pub fn new(inner: Box<dyn Progress>) -> Self {
        Recorder {
            inner,
            open: Mutex::new(None),
        }
    }

    fn close(&self) {
        let Ok(mut open) = self.open.lock() else {
            return;
        };
        if let Some((name, mark)) = open.take() {
            let stage = Stage {
                name,
                span: mark.span(),
            };
            if let Ok(mut log) = LOG.lock() {
                log.stages.push(stage);
            }
        }
    }
}

impl Progress for Recorder {
    fn begin(&self, stage: &str, total: u64) {
        self.close();
        if let Ok(mut open) = self.open.lock() {
            *open = Some((stage.to_string(), Mark::now()));
        }
        self.inner.begin(stage, total);
    }

    fn advance(&self, n: u64) {
        self.inner.advance(n);
    }

    fn end(&self) {
        self.close();
        self.inner.end();
    }
}

impl Drop for Recorder {
    fn drop(&mut self) {
        self.close();
    }
}

/// Records that `skipped` records of the input `source` were dropped while
/// reading it and `left_out` not processed, for the summary line and the
/// report.
pub fn input_skipped(source: &str, skipped: u64, left_out: LeftOut) {
    if let Ok(mut log) = LOG.lock() {
        log.skipped = Some((source.to_string(), skipped));
        log.left_out = Some(left_out);
    }
}

/// Records that the output holds the unselected points, flagged
/// (`--unselected keep`), for the summary line.
pub fn unselected_kept(kept: bool) {
    if let Ok(mut log) = LOG.lock() {
        log.kept = kept;
    }
}

/// Records the audit of the mesh the run wrote, for the report.
pub fn mesh_audit(audit: &MeshAudit) {
    if let Ok(mut log) = LOG.lock() {
        log.audit = Some(*audit);
    }
}

/// Records the audit a broken promise carries (the mesh was written as
/// incomplete), when `e` is one.
pub fn broken_promise(e: Option<&MeshError>) {
    if let Some(MeshError::PromiseBroken { audit, .. }) = e {
        mesh_audit(audit);
    }
}

/// The words the summary line ends with when records were left out.
fn left_out_note(source: &str, l: &LeftOut, kept: bool) -> String {
    let records = if l.total() == 1 { "record" } else { "records" };
    let output = match (kept, l.unselected > 0) {
        (true, true) => "; the unselected are in the output, flagged 128 (--unselected keep)",
        (false, true) => "; not in the output (--unselected drop)",
        _ => "",
    };
    format!(
        "{} {records} of {source} left out: {}{output}",
        l.total(),
        l.describe()
    )
}

/// The words the summary line ends with when records were dropped.
fn skipped_note(source: &str, n: u64) -> String {
    let records = if n == 1 { "record" } else { "records" };
    format!(
        "{n} {records} skipped (non-finite coordinates or a cut last line, --skip-invalid; or marked invalid by the file) from {source}"
    )
}

/// Prints a command's closing summary line and keeps it for the report;
/// the records dropped from its input, if any, are told at its end.
pub fn summary(line: String) {
    let (skipped, left_out, kept) = match LOG.lock() {
        Ok(log) => (log.skipped.clone(), log.left_out, log.kept),
        Err(_) => (None, None, false),
    };
    let mut line = match &skipped {
        Some((source, n)) if *n > 0 => format!("{line}; {}", skipped_note(source, *n)),
        _ => line,
    };
    if let (Some((source, _)), Some(l)) = (&skipped, left_out.filter(|l| l.total() > 0)) {
        line = format!("{line}; {}", left_out_note(source, &l, kept));
    }
    // A closed pipe (`| head`) is the reader's choice, not an error of ours.
    let _ = writeln!(std::io::stdout(), "{line}");
    if let Ok(mut log) = LOG.lock() {
        log.summary = Some(line);
    }
}

/// The summary line printed last, if any.
pub fn last_summary() -> Option<String> {
    LOG.lock().ok()?.summary.clone()
}

/// Writes the report of this run to `path`: `start` is when the command
/// began, `outcome` its result.
pub fn write(path: &Path, start: &Mark, outcome: &anyhow::Result<()>) -> anyhow::Result<()> {
    let (stages, summary, skipped, left_out, mesh_audit) = match LOG.lock() {
        Ok(log) => (
            log.stages.clone(),
            log.summary.clone(),
            log.skipped.clone(),
            log.left_out,
            log.audit,
        ),
        Err(_) => (Vec::new(), None, None, None, None),
    };
    let outcome = match outcome {
        Ok(()) => "ok".to_string(),
        Err(e) => format!(
            "error: {}",
            e.chain()
                .map(|c| c.to_string())
                .collect::<Vec<_>>()
                .join(": ")
        ),
    };
    let report = Report {
        scanmesh_version: env!("CARGO_PKG_VERSION"),
        args: std::env::args().collect(),
        outcome,
        summary,
        skipped_invalid: skipped.map(|(_, n)| n),
        left_out,
        mesh_audit,
        total: start.span(),
        stages,
    };
    let text = serde_json::to_string_pretty(&report)?;
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned());
    let tmp = path.with_file_name(format!(".{}.tmp", name.unwrap_or_default()));
    let written = std::fs::write(&tmp, text + "\n").and_then(|()| std::fs::rename(&tmp, path));
    if let Err(e) = written {
        let _ = std::fs::remove_file(&tmp);
        anyhow::bail!("--report {}: {e}", path.display());
    }
    Ok(())
}
