//! The commands' standard output. A reader that stops early (`scanmesh
//! status DIR | head -2`) closes the pipe, and `println!` panics on the
//! next write. Writes here return [`Closed`] instead, which `main` turns
//! into a quiet, successful exit (as ripgrep does): stopping early was the
//! reader's choice, not a failure of ours.

use std::io::{ErrorKind, Write};

/// Standard output was closed by its reader.
#[derive(Debug, thiserror::Error)]
#[error("standard output was closed by its reader")]
pub struct Closed;

/// Writes `args` to standard output.
pub fn write(args: std::fmt::Arguments) -> anyhow::Result<()> {
    match std::io::stdout().lock().write_fmt(args) {
        Ok(()) => Ok(()),
        Err(e) if e.kind() == ErrorKind::BrokenPipe => Err(Closed.into()),
        Err(e) => Err(anyhow::Error::new(e).context("writing to standard output")),
    }
}

/// Whether `err` is (caused by) a closed standard output.
pub fn closed(err: &anyhow::Error) -> bool {
    err.chain().any(|cause| cause.is::<Closed>())
}

/// `println!` that returns an error when standard output is closed.
macro_rules! outln {
    ($($arg:tt)*) => {
        $crate::cli::stdout::write(format_args!("{}\n", format_args!($($arg)*)))
    };
}
pub(crate) use outln;
