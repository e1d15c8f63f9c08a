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
    /// `buf` holds the input's last line, which has no end of line: a
    /// record there may have been cut inside its last number, so readers
    /// of records do not take it as whole.
    Unterminated,
    Eof,
    TooLong,
}

impl Line {
    /// Whether `buf` holds a line (ended or not).
    pub(crate) fn is_line(&self) -> bool {
        matches!(self, Line::Read | Line::Unterminated)
    }
}

/// Reads the next line into `buf` (cleared first).
pub(crate) fn read_line<R: BufRead + ?Sized>(r: &mut R, buf: &mut Vec<u8>) -> io::Result<Line> {
    buf.clear();
    let n = Read::take(&mut *r, MAX_LINE + 1).read_until(b'\n', buf)?;
    if n == 0 {
        return Ok(Line::Eof);
    }
    let ended = buf.last() == Some(&b'\n');
    if ended {
        buf.pop();
    } else if n as u64 > MAX_LINE {
        return Ok(Line::TooLong);
    }
    if buf.last() == Some(&b'\r') {
        buf.pop();
    }
    Ok(if ended {
        Line::Read
    } else {
        Line::Unterminated
    })
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_last_line_without_end_of_line_is_told_apart() {
        let mut r: &[u8] = b"1 2 3\r\n4 5 6\n7 8 9.2";
        let mut buf = Vec::new();
        let mut got = Vec::new();
        loop {
            let line = read_line(&mut r, &mut buf).unwrap();
            if line == Line::Eof {
                break;
            }
            got.push((line, String::from_utf8(buf.clone()).unwrap()));
        }
        assert_eq!(
            got,
            [
                (Line::Read, "1 2 3".to_string()),
                (Line::Read, "4 5 6".to_string()),
                (Line::Unterminated, "7 8 9.2".to_string()),
            ]
        );
    }
}
