//! What a run did and what it cost ([`RunLog`]), for the morning after an
//! overnight run and for regression benches: every stage a command reports
//! through a [`TimedProgress`] is timed (wall, CPU, peak RSS, storage
//! bytes, [`crate::telemetry`]), whatever the terminal shows; the command's
//! summary line, the input records it dropped or left out, whether the
//! unselected points were kept and the audit of the mesh it wrote are
//! recorded beside them; [`RunLog::write_json`] writes it all, with the
//! outcome, as one JSON file that appears whole or not at all
//! ([`AtomicFile`]).
//!
//! Input records a reader dropped (`--skip-invalid`, or records the file
//! marks invalid) are told at the end of the summary line
//! ([`RunLog::summary`]) and in the report (`skipped_invalid`) whatever the
//! command, so nobody joins an output to its input by position unwarned.
//! This module prints nothing: the caller prints the line it returns, the
//! report's outcome in words ([`outcome_words`]), and each stage's cost as
//! a line when asked ([`StageLines`], `SCANMESH_TIMINGS`).

use crate::io::{AtomicFile, IoError, LeftOut};
use crate::mesh::{MeshAudit, MeshError};
use crate::progress::Progress;
use crate::telemetry::{Mark, Span};
use serde::Serialize;
use std::path::Path;
use std::sync::{Arc, Mutex};

/// One timed stage of a run.
#[derive(Clone, Debug, Serialize)]
pub struct Stage {
    /// The stage's name, as the command reported it.
    pub name: String,
    /// What the stage cost.
    #[serde(flatten)]
    pub span: Span,
}

/// The stages and summary of one run, and what it left out of its input.
#[derive(Debug)]
pub struct RunLog {
    /// When the run began.
    start: Mark,
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

#[derive(Serialize)]
struct Report<'a> {
    scanmesh_version: &'a str,
    /// The command line, as given.
    args: &'a [String],
    /// "ok", or the error and its causes.
    outcome: &'a str,
    summary: Option<&'a str>,
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
    stages: &'a [Stage],
}

impl Default for RunLog {
    fn default() -> Self {
        RunLog::new()
    }
}

impl RunLog {
    /// An empty log of a run that begins now.
    pub fn new() -> Self {
        RunLog {
            start: Mark::now(),
            stages: Vec::new(),
            summary: None,
            skipped: None,
            left_out: None,
            kept: false,
            audit: None,
        }
    }

    /// Records a stage and what it cost.
    pub fn stage(&mut self, name: String, span: Span) {
        self.stages.push(Stage { name, span });
    }

    /// The stages recorded so far, in the order they ended.
    pub fn stages(&self) -> &[Stage] {
        &self.stages
    }

    /// Records that `skipped` records of the input `source` were dropped
    /// while reading it and `left_out` not processed, for the summary line
    /// and the report.
    pub fn input_skipped(&mut self, source: &str, skipped: u64, left_out: LeftOut) {
        self.skipped = Some((source.to_string(), skipped));
        self.left_out = Some(left_out);
    }

    /// Records whether the output holds the unselected points, flagged
    /// (`--unselected keep`), for the summary line.
    pub fn unselected_kept(&mut self, kept: bool) {
        self.kept = kept;
    }

    /// Records the audit of the mesh the run wrote, for the report.
    pub fn mesh_audit(&mut self, audit: &MeshAudit) {
        self.audit = Some(*audit);
    }

    /// Records the audit a broken promise carries (the mesh was written as
    /// incomplete), when `e` is one.
    pub fn broken_promise(&mut self, e: Option<&MeshError>) {
        if let Some(MeshError::PromiseBroken { audit, .. }) = e {
            self.mesh_audit(audit);
        }
    }

    /// Keeps a command's closing summary `line`, the records dropped from
    /// or left out of its input told at its end, and returns it, to print.
    pub fn summary(&mut self, line: impl std::fmt::Display) -> String {
        let line = line.to_string();
        let mut line = match &self.skipped {
            Some((source, n)) if *n > 0 => format!("{line}; {}", skipped_note(source, *n)),
            _ => line,
        };
        if let (Some((source, _)), Some(l)) =
            (&self.skipped, self.left_out.filter(|l| l.total() > 0))
        {
            line = format!("{line}; {}", left_out_note(source, &l, self.kept));
        }
        self.summary = Some(line.clone());
        line
    }

    /// The summary line kept last, if any.
    pub fn last_summary(&self) -> Option<&str> {
        self.summary.as_deref()
    }

    /// Writes the report of this run to `path` as JSON: `version` the
    /// program's, `args` its command line, `outcome` "ok" or the error;
    /// the run's total cost is measured now. The file appears whole or not
    /// at all.
    pub fn write_json(
        &self,
        path: &Path,
        version: &str,
        args: &[String],
        outcome: &str,
    ) -> Result<(), IoError> {
        let report = Report {
            scanmesh_version: version,
            args,
            outcome,
            summary: self.summary.as_deref(),
            skipped_invalid: self.skipped.as_ref().map(|(_, n)| *n),
            left_out: self.left_out,
            mesh_audit: self.audit,
            total: self.start.span(),
            stages: &self.stages,
        };
        let mut text = serde_json::to_string_pretty(&report)
            .map_err(|e| IoError::os(path, std::io::Error::other(e)))?;
        text.push('\n');
        let mut file = AtomicFile::create(path)?;
        std::io::Write::write_all(file.file(), text.as_bytes())
            .map_err(|e| IoError::os(path, e))?;
        file.commit()
    }
}

/// A run's outcome as its report words it: `ok`, or `error: ` and the
/// error with its causes, joined by `: `.
pub fn outcome_words(outcome: Result<(), &(dyn std::error::Error + 'static)>) -> String {
    let Err(err) = outcome else {
        return "ok".to_string();
    };
    let chain = std::iter::successors(Some(err), |e| e.source());
    let words: Vec<String> = chain.map(|c| c.to_string()).collect();
    format!("error: {}", words.join(": "))
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

/// A [`RunLog`] shared between the code that runs a command and the
/// progress reporters that time its stages.
#[derive(Clone, Debug, Default)]
pub struct SharedRunLog(Arc<Mutex<RunLog>>);

impl SharedRunLog {
    /// An empty log of a run that begins now.
    pub fn new() -> Self {
        SharedRunLog(Arc::new(Mutex::new(RunLog::new())))
    }

    /// Runs `f` on the log (a panic elsewhere leaves it as it was).
    pub fn with<T>(&self, f: impl FnOnce(&mut RunLog) -> T) -> T {
        let mut log = self.0.lock().unwrap_or_else(|e| e.into_inner());
        f(&mut log)
    }

    /// A progress reporter showing `inner` and timing every stage into this
    /// log.
    pub fn timed(&self, inner: Box<dyn Progress>) -> TimedProgress {
        TimedProgress {
            inner,
            log: self.clone(),
            open: Mutex::new(None),
        }
    }
}

/// Times the stages `inner` shows into a [`RunLog`] ([`SharedRunLog::timed`]).
pub struct TimedProgress {
    inner: Box<dyn Progress>,
    log: SharedRunLog,
    open: Mutex<Option<(String, Mark)>>,
}

impl TimedProgress {
    fn close(&self) {
        let Ok(mut open) = self.open.lock() else {
            return;
        };
        if let Some((name, mark)) = open.take() {
            let span = mark.span();
            self.log.with(|log| log.stage(name, span));
        }
    }
}

impl Progress for TimedProgress {
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

impl Drop for TimedProgress {
    fn drop(&mut self) {
        self.close();
    }
}

/// Each stage's cost as a line, for profiling runs (`SCANMESH_TIMINGS`):
/// the wall time, the process CPU time (all threads; steadier than wall
/// time on a shared machine), the RSS at the end and the peak RSS so far
/// (to see which stage sets it), and the bytes read from and written to
/// storage. Time spent between stages (store setup, spacing, dropping and
/// removing scratch data) is a line `(between stages)`, so no cost hides.
/// Each line goes to the sink the caller gives (the CLI: stderr).
pub struct StageLines {
    start: Mutex<Option<(String, Mark)>>,
    last_end: Mutex<Mark>,
    sink: Box<dyn Fn(&str) + Send + Sync>,
}

impl StageLines {
    /// Lines from now on, each handed to `sink`.
    pub fn new(sink: impl Fn(&str) + Send + Sync + 'static) -> Self {
        StageLines {
            start: Mutex::new(None),
            last_end: Mutex::new(Mark::now()),
            sink: Box::new(sink),
        }
    }

    fn gap(&self) {
        if let Ok(mut last) = self.last_end.lock() {
            if last.elapsed().as_secs_f64() >= 0.005 {
                (self.sink)(&format!("{:>24}: {}", "(between stages)", last.span()));
            }
            *last = Mark::now();
        }
    }
}

impl Drop for StageLines {
    fn drop(&mut self) {
        self.gap();
    }
}

impl Progress for StageLines {
    fn begin(&self, stage: &str, _: u64) {
        self.gap();
        if let Ok(mut s) = self.start.lock() {
            *s = Some((stage.to_string(), Mark::now()));
        }
    }

    fn advance(&self, _: u64) {}

    fn end(&self) {
        if let Ok(mut s) = self.start.lock() {
            if let Some((stage, t0)) = s.take() {
                (self.sink)(&format!("{stage:>24}: {}", t0.span()));
                if let Ok(mut last) = self.last_end.lock() {
                    *last = Mark::now();
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::progress::NoProgress;

    #[test]
    fn stages_are_timed_and_the_summary_tells_what_was_skipped() {
        let log = SharedRunLog::new();
        {
            let p = log.timed(Box::new(NoProgress));
            p.begin("read", 10);
            p.begin("write", 10);
            p.end();
        }
        let names: Vec<String> = log.with(|l| l.stages().iter().map(|s| s.name.clone()).collect());
        assert_eq!(names, ["read", "write"]);
        let line = log.with(|l| {
            l.input_skipped("in.xyz", 1, LeftOut::default());
            l.summary("normals: 15 points")
        });
        assert!(
            line.starts_with("normals: 15 points; 1 record skipped"),
            "{line}"
        );
        assert!(line.ends_with("from in.xyz"), "{line}");
        assert_eq!(log.with(|l| l.last_summary().map(String::from)), Some(line));
    }

    #[test]
    fn the_outcome_is_worded_with_its_causes() {
        assert_eq!(outcome_words(Ok(())), "ok");
        let inner = std::io::Error::other("disk full");
        let outer = IoError::os(Path::new("out.ply"), inner);
        assert_eq!(
            outcome_words(Err(&outer)),
            "error: out.ply: disk full: disk full"
        );
    }

    #[test]
    fn the_report_is_written_whole() {
        let dir = tempfile::tempdir().expect("tmp");
        let path = dir.path().join("run.json");
        let mut log = RunLog::new();
        log.summary("done");
        log.write_json(&path, "1.2.3", &["scanmesh".into()], "ok")
            .expect("written");
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&path).expect("read")).expect("json");
        assert_eq!(json["scanmesh_version"], "1.2.3");
        assert_eq!(json["outcome"], "ok");
        assert_eq!(json["summary"], "done");
        assert!(json["skipped_invalid"].is_null());
        let names: Vec<_> = std::fs::read_dir(dir.path()).expect("list").collect();
        assert_eq!(names.len(), 1, "{names:?}");
    }
}
