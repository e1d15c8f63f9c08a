//! XYZ / CSV text point reader (`.xyz`, `.txt`, `.csv`, `.pts`, each
//! optionally gzipped).
//!
//! Layout rules:
//! - fields are separated by whitespace and/or commas (or semicolons);
//! - blank lines and lines starting with `#` or `//` are skipped anywhere;
//! - the first remaining line is a header, and skipped, when it is not a
//!   point: a non-numeric field among its first three, or fewer than three
//!   fields (like the count line of `.pts`);
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
}

fn split_fields(s: &str) -> impl Iterator<Item = &str> {
    s.split(|c: char| c == ',' || c == ';' || c.is_ascii_whitespace())
        .filter(|t| !t.is_empty())
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
                Line::Read => self.line_no += 1,
            }
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
            let numeric = split_fields(s)
                .take_while(|t| t.parse::<f64>().is_ok())
                .count();
            if numeric >= 3 {
                let columns = if numeric >= 6 { 6 } else { 3 };
                self.columns = Some(columns);
                self.info.has_normals = columns == 6;
                self.pending = true;
                return Ok(());
            }
            if header_seen {
                return Err(self.bad("expected at least 3 numeric columns x y z".into()));
            }
            header_seen = true;
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
