//! `--report FILE.json`: this process's one run log (the library's
//! [`SharedRunLog`]: stages timed, summary line, input records dropped or
//! left out, mesh audit), the summary line printed, and the report written
//! when the flag asks for it, with the outcome in words.

use scanmesh::runlog::SharedRunLog;
use std::fmt::Display;
use std::io::Write;
use std::path::Path;
use std::sync::LazyLock;

/// The log of this process's run, begun when first asked for.
static LOG: LazyLock<SharedRunLog> = LazyLock::new(SharedRunLog::new);

/// The log of this process's run.
pub fn log() -> &'static SharedRunLog {
    &LOG
}

/// Prints a command's closing summary line and keeps it for the report;
/// the records dropped from its input, if any, are told at its end.
pub fn summary(line: impl Display) {
    let line = LOG.with(|log| log.summary(line));
    // A closed pipe (`| head`) is the reader's choice, not an error of ours.
    let _ = writeln!(std::io::stdout(), "{line}");
}

/// Writes the report of this run to `path`, `outcome` its result.
pub fn write(path: &Path, outcome: &anyhow::Result<()>) -> anyhow::Result<()> {
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
    let args: Vec<String> = std::env::args().collect();
    LOG.with(|log| log.write_json(path, env!("CARGO_PKG_VERSION"), &args, &outcome))
        .map_err(|e| anyhow::anyhow!("--report {e}"))
}
