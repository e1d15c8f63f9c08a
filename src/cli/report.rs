//! `--report FILE.json`: what a run did and what it cost, for the morning
//! after an overnight run and for regression benches. Every stage a
//! command reports through [`Progress`] is timed here (wall, CPU, peak RSS,
//! storage bytes), whatever the terminal shows; the command's summary line
//! and its outcome (or error) close the report. The file appears whole or
//! not at all (written beside, then renamed).

use super::clock::{Mark, Span};
use scanmesh::pipeline::Progress;
use serde::Serialize;
use std::io::Write;
use std::path::Path;
use std::sync::Mutex;

/// Stages and summary of this process's run.
static LOG: Mutex<Log> = Mutex::new(Log {
    stages: Vec::new(),
    summary: None,
});

struct Log {
    stages: Vec<Stage>,
    summary: Option<String>,
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

/// Prints a command's closing summary line and keeps it for the report.
pub fn summary(line: String) {
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
    let (stages, summary) = match LOG.lock() {
        Ok(log) => (log.stages.clone(), log.summary.clone()),
        Err(_) => (Vec::new(), None),
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
