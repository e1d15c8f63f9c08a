//! Line reading shared by the text formats (ASCII PLY, XYZ/CSV, OBJ): one
//! reused byte buffer, a bound on line length so a binary file mistaken for
//! text cannot be slurped whole, and CR/LF endings.

use std::io::{self, BufRead, Read};

/// Longest accepted line. Real point records are < 1 KiB.
pub(crate) const MAX_LINE: u64 = 1 << 20;

#[derive(Debug, PartialEq, Eq)]
pub(crate) enum Line {
    /// `buf` holds the line without its terminator.
    Read,
    Eof,
    TooLong,
}

/// Reads the next line into `buf` (cleared first).
pub(crate) fn read_line<R: BufRead + ?Sized>(r: &mut R, buf: &mut Vec<u8>) -> io::Result<Line> {
    buf.clear();
    let n = Read::take(&mut *r, MAX_LINE + 1).read_until(b'\n', buf)?;
    if n == 0 {
        return Ok(Line::Eof);
    }
    if buf.last() == Some(&b'\n') {
        buf.pop();
    } else if n as u64 > MAX_LINE {
        return Ok(Line::TooLong);
    }
    if buf.last() == Some(&b'\r') {
        buf.pop();
    }
    Ok(Line::Read)
}

/// The line as text, or a reason it is not.
pub(crate) fn as_text(buf: &[u8]) -> Result<&str, String> {
    std::str::from_utf8(buf).map_err(|_| "not valid UTF-8 text (binary data?)".to_string())
}

/// Parses one numeric field, naming it in the error.
pub(crate) fn parse_f64(tok: &str, what: &str) -> Result<f64, String> {
    tok.parse::<f64>()
        .map_err(|_| format!("{what}: '{}' is not a number", shorten(tok)))
}

/// Parses one f32 field (PLY `float`, normals), naming it in the error.
pub(crate) fn parse_f32(tok: &str, what: &str) -> Result<f32, String> {
    tok.parse::<f32>()
        .map_err(|_| format!("{what}: '{}' is not a number", shorten(tok)))
}

/// At most 40 characters of a token, for error messages about garbage.
pub(crate) fn shorten(tok: &str) -> String {
    tok.chars().take(40).collect()
}
