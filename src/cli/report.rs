//! `--report FILE.json`: the summary line printed and kept in the run's
//! log (the library's [`SharedRunLog`]: stages timed, summary line, input
//! records dropped or left out, mesh audit; one per command line, carried
//! by its `CommonArgs` into `Settings`), and the report written when the
//! flag asks for it, with the outcome in words.

use scanmesh::runlog::{outcome_words, SharedRunLog};
use std::fmt::Display;
use std::io::Write;
use std::path::Path;

/// Prints a command's closing summary line and keeps it in `log` for the
/// report; the records dropped from its input, if any, are told at its end.
pub fn summary(log: &SharedRunLog, line: impl Display) {
    let line = log.with(|log| log.summary(line));
    // A closed pipe (`| head`) is the reader's choice, not an error of ours.
    let _ = writeln!(std::io::stdout(), "{line}");
}

/// Writes the report of the run `log` holds to `path`, `outcome` its result.
pub fn write(log: &SharedRunLog, path: &Path, outcome: &anyhow::Result<()>) -> anyhow::Result<()> {
    let outcome = outcome_words(outcome.as_ref().map(|_| ()).map_err(|e| e.as_ref() as _));
    let args: Vec<String> = std::env::args().collect();
    log.with(|log| log.write_json(path, env!("CARGO_PKG_VERSION"), &args, &outcome))
        .map_err(|e| anyhow::anyhow!("--report {e}"))
}
