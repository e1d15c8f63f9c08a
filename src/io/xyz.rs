//! XYZ / CSV text point reader (`.xyz`, `.txt`, `.csv`, `.pts`, each
//! optionally gzipped).
//!
//! Layout rules:
//! - fields are separated by whitespace and/or commas (or semicolons);
//! - blank lines and lines starting with `#` or `//` are skipped anywhere;
//! - the first remaining line is a header, and skipped, only when it looks
//!   like one: every field a column name (`x`, `Y`, `"z"`, `nx`: no field a
//!   number or starting like one), or a lone integer (the point count line
//!   of `.pts`). A first line mixing numbers and other text (`1.0 2.0
//!   x3.0`) is an error, not a header: it is a damaged point;
//! - the last line must end with an end of line: without one it may be cut
//!   inside its last number (`3.25` read as `3.2`), so it is an error, or
//!   under [`InvalidPolicy::Skip`] dropped and counted like a non-finite
//!   record. Blank and comment lines are exempt. A gzip stream cut short is
//!   an error of the decompressor already;
//! - the first data line fixes the layout: with 6 or more numeric columns,
//!   columns 4-6 are the normal `nx ny nz`; with 3-5, only `x y z` are read.
//!   Every later line must have at least as many columns as that layout
//!   reads; columns beyond it (colours, intensity) are ignored, not parsed.
//!
//! Errors name the line number (1-based, as in an editor); `record` in them is
//! the 0-based index of the data record.

use super::policy::Admitter;
use super::source::Input;
use super::text::{self, Line};
use super::{Format, InvalidPolicy, IoError, PointChunk, PointReader, SourceInfo};
use glam::{DVec3, Vec3};
use std::path::Path;

pub struct XyzReader {
    info: SourceInfo,
    input: Input,
    admit: Admitter,
    line: Vec<u8>,
    line_no: u64,
    /// Data records consumed (kept or skipped).
    next: u64,
    /// Columns read per line: 3 or 6; `None` when there is no data line.
    columns: Option<usize>,
    /// `line` holds a data line not consumed yet (the one `open` read).
    pending: bool,
    /// `line` is the input's last line and has no end of line.
    unterminated: bool,
}

fn split_fields(s: &str) -> impl Iterator<Item = &str> {
    s.split(|c: char| c == ',' || c == ';' || c.is_ascii_whitespace())
        .filter(|t| !t.is_empty())
}

/// What the first line that is no comment holds.
#[derive(Debug, PartialEq, Eq)]
enum FirstLine {
    /// A point: read 3 columns, or 6 (with the normal).
    Point(usize),
    /// Column names, or the point count of `.pts`: skipped.
    Header,
}

/// A column name: neither a number nor starting like one, so a field cut
/// or damaged out of a number (`x3.0`, `3.0x`, `-`) is not taken for one.
fn is_name(tok: &str) -> bool {
    let numberlike = |c: char| c.is_ascii_digit() || matches!(c, '+' | '-' | '.');
    tok.parse::<f64>().is_err() && !tok.starts_with(numberlike)
}

fn first_line(s: &str) -> Option<FirstLine> {
    let fields: Vec<&str> = split_fields(s).collect();
    let numeric = fields
        .iter()
        .take_while(|t| t.parse::<f64>().is_ok())
        .count();
    if numeric >= 3 {
        return Some(FirstLine::Point(if numeric >= 6 { 6 } else { 3 }));
    }
    let names = !fields.is_empty() && fields.iter().all(|t| is_name(t));
    let count_line = matches!(fields[..], [n] if n.parse::<u64>().is_ok());
    (names || count_line).then_some(FirstLine::Header)
}

/// Blank or comment line (checked on bytes: no UTF-8 validation twice).
fn is_comment(line: &[u8]) -> bool {
    let s = line.trim_ascii_start();
    s.is_empty() || s.starts_with(b"#") || s.starts_with(b"//")
}

impl XyzReader {
    /// Opens a text point file. The layout (3 or 6 columns) is known after
    /// the first data line, so `info().has_normals` is settled here by
    /// reading ahead to it.
    pub(crate) fn open(
        path: &Path,
        input: Input,
        gzip: bool,
        policy: InvalidPolicy,
    ) -> Result<Self, IoError> {
        let info = SourceInfo {
            path: path.to_path_buf(),
            format: Format::Xyz,
            gzip,
            declared_count: None,
            has_normals: false,
            attributes: crate::io::AttributeSet::EMPTY,
            header_bounds: None,
            las_transform: None,
        };
        let mut r = XyzReader {
            info,
            input,
            admit: Admitter::new(path.to_path_buf(), policy),
            line: Vec::new(),
            line_no: 0,
            next: 0,
            columns: None,
            pending: false,
            unterminated: false,
        };
        r.find_first_record()?;
        Ok(r)
    }

    fn bad(&self, reason: String) -> IoError {
        IoError::BadRecord {
            path: self.info.path.clone(),
            record: self.next,
            reason: format!("line {}: {reason}", self.line_no),
        }
    }

    /// Reads the next non-comment line into `self.line`; false at the end.
    fn next_line(&mut self) -> Result<bool, IoError> {
        loop {
            let got = text::read_line(&mut self.input, &mut self.line)
                .map_err(|e| IoError::os(&self.info.path, e))?;
            match got {
                Line::Eof => return Ok(false),
                Line::TooLong => {
                    self.line_no += 1;
                    return Err(self.bad(format!("longer than {} bytes", text::MAX_LINE)));
                }
                Line::Read | Line::Unterminated => self.line_no += 1,
            }
            self.unterminated = got == Line::Unterminated;
            if !is_comment(&self.line) {
                return Ok(true);
            }
        }
    }

    /// Skips a header line if there is one and settles the column layout,
    /// leaving the first data line in `self.line`.
    fn find_first_record(&mut self) -> Result<(), IoError> {
        let mut header_seen = false;
        while self.next_line()? {
            let s = text::as_text(&self.line).map_err(|e| self.bad(e))?;
            match first_line(s) {
                Some(FirstLine::Point(columns)) => {
                    self.columns = Some(columns);
                    self.info.has_normals = columns == 6;
                    self.pending = true;
                    return Ok(());
                }
                // A cut first line is still a point: `read_chunk` says so.
                None if self.unterminated => {
                    self.columns = Some(3);
                    self.pending = true;
                    return Ok(());
                }
                Some(FirstLine::Header) if !header_seen => header_seen = true,
                Some(FirstLine::Header) => {
                    return Err(self.bad("expected at least 3 numeric columns x y z".into()))
                }
                None => {
                    let line = text::shorten(s);
                    return Err(self.bad(format!(
                        "'{line}' is neither a point (at least 3 numbers: x y z) nor a header of column names"
                    )));
                }
            }
        }
        Ok(())
    }

    /// Parses `self.line` as a record of `columns` fields.
    fn parse_record(&self, columns: usize) -> Result<(DVec3, Vec3), IoError> {
        const NAMES: [&str; 6] = ["x", "y", "z", "nx", "ny", "nz"];
        let s = text::as_text(&self.line).map_err(|e| self.bad(e))?;
        let mut v = [0.0f64; 6];
        let mut fields = split_fields(s);
        for (k, slot) in v.iter_mut().enumerate().take(columns) {
            let tok = fields
                .next()
                .ok_or_else(|| self.bad(format!("{k} columns, expected at least {columns}")))?;
            // Normals are f32: parse them as such, not via a rounded f64.
            *slot = match k < 3 {
                true => text::parse_f64(tok, NAMES[k]),
                false => text::parse_f32(tok, NAMES[k]).map(f64::from),
            }
            .map_err(|e| self.bad(e))?;
        }
        let p = DVec3::new(v[0], v[1], v[2]);
        Ok((p, Vec3::new(v[3] as f32, v[4] as f32, v[5] as f32)))
    }
}

impl PointReader for XyzReader {
    fn info(&self) -> &SourceInfo {
        &self.info
    }

    /// `max` of 0 is taken as 1, since 0 points read means end of input.
    fn read_chunk(&mut self, chunk: &mut PointChunk, max: usize) -> Result<usize, IoError> {
        let max = max.max(1);
        self.admit.begin(chunk, self.next, &self.info);
        let Some(columns) = self.columns else {
            return Ok(0);
        };
        while chunk.len() < max {
            if !std::mem::take(&mut self.pending) && !self.next_line()? {
                break;
            }
            if self.unterminated {
                self.admit.cut(chunk, self.next, self.line_no)?;
                self.next += 1;
                continue;
            }
            let (p, n) = self.parse_record(columns)?;
            self.admit.push(chunk, self.next, p, n)?;
            self.next += 1;
        }
        Ok(self.admit.end(chunk))
    }

    fn skipped(&self) -> u64 {
        self.admit.skipped()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn reader(text: &str, policy: InvalidPolicy) -> Result<XyzReader, IoError> {
        let input: Input = Box::new(std::io::Cursor::new(text.as_bytes().to_vec()));
        XyzReader::open(Path::new("t.xyz"), input, false, policy)
    }

    /// The points read, the records skipped, or the first error.
    fn read(text: &str, policy: InvalidPolicy) -> Result<(Vec<DVec3>, u64), IoError> {
        let mut r = reader(text, policy)?;
        let mut chunk = PointChunk::default();
        let mut all = Vec::new();
        while r.read_chunk(&mut chunk, 2)? > 0 {
            all.extend_from_slice(&chunk.xyz);
        }
        Ok((all, r.skipped()))
    }

    #[test]
    fn a_first_line_is_a_header_only_when_it_looks_like_one() {
        for header in [
            "x y z",
            "X,Y,Z,R,G,B",
            "\"x\";\"y\";\"z\"",
            "nx ny nz x y z",
            "12345",
        ] {
            assert_eq!(first_line(header), Some(FirstLine::Header), "{header}");
        }
        assert_eq!(first_line("1 2 3"), Some(FirstLine::Point(3)));
        assert_eq!(first_line("1,2,3,0,0,1,255"), Some(FirstLine::Point(6)));
        for damaged in ["1.0 2.0 x3.0", "1.0 2.0", "x 2.0 z", "1.0 2.0 3.0x", "-"] {
            assert_eq!(first_line(damaged), None, "{damaged}");
        }
    }

    #[test]
    fn a_damaged_first_line_is_an_error_naming_it() {
        let e = read("1.0 2.0 x3.0\n4 5 6\n", InvalidPolicy::Skip).unwrap_err();
        assert!(matches!(e, IoError::BadRecord { record: 0, .. }), "{e:?}");
        let msg = e.to_string();
        assert!(
            msg.contains("t.xyz") && msg.contains("line 1") && msg.contains("x3.0"),
            "{msg}"
        );
        // A real header is skipped, its points read.
        let (got, _) = read("x y z\n4 5 6\n", InvalidPolicy::Reject).unwrap();
        assert_eq!(got, [DVec3::new(4.0, 5.0, 6.0)]);
    }

    #[test]
    fn a_last_line_without_end_of_line_is_cut_or_skipped() {
        let text = "1 2 3\n4 5 6\n7 8 9.2";
        match read(text, InvalidPolicy::Reject) {
            Err(IoError::CutShort {
                record: 2, line: 3, ..
            }) => {}
            other => panic!("{other:?}"),
        }
        let (got, skipped) = read(text, InvalidPolicy::Skip).unwrap();
        assert_eq!(got.len(), 2);
        assert_eq!(skipped, 1);
        // Cut in the first and only line, even one that looks like no point.
        for cut in ["7 8 9.2", "7 8"] {
            assert!(matches!(
                read(cut, InvalidPolicy::Reject),
                Err(IoError::CutShort { line: 1, .. })
            ));
            assert_eq!(read(cut, InvalidPolicy::Skip).unwrap(), (vec![], 1));
        }
        assert_eq!(read("1 2 3\n", InvalidPolicy::Reject).unwrap().0.len(), 1);
    }
}
