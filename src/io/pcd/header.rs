//! The PCD header (PCL's Point Cloud Data format, v0.5-0.7): `FIELDS`,
//! `SIZE`, `TYPE`, `COUNT`, `WIDTH`, `HEIGHT`, `VIEWPOINT`, `POINTS`, then
//! `DATA ascii|binary|binary_compressed` as the last header line. Counts are
//! checked against each other, never used to size an allocation.

use crate::io::text::{as_text, read_line, Line};
use std::io::BufRead;

/// How the body is stored.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Data {
    /// One text line per point.
    Ascii,
    /// Fixed-size records, fields in order (array of structures).
    Binary,
    /// One LZF block of the fields one after the other, each for every point
    /// (structure of arrays).
    Compressed,
}

/// A scalar type of a field.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scalar {
    I(usize),
    U(usize),
    F(usize),
}

impl Scalar {
    pub fn size(self) -> usize {
        match self {
            Scalar::I(s) | Scalar::U(s) | Scalar::F(s) => s,
        }
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct Field {
    pub name: String,
    pub scalar: Scalar,
    pub count: usize,
}

impl Field {
    pub fn bytes(&self) -> usize {
        self.scalar.size() * self.count
    }
}

#[derive(Clone, Debug)]
pub struct PcdHeader {
    pub fields: Vec<Field>,
    pub points: u64,
    /// Rows: an organised cloud (a depth camera's frame) has `height > 1`,
    /// its points row after row, `WIDTH` a row.
    pub height: u64,
    pub data: Data,
    /// Header lines read (for error messages in ASCII bodies).
    pub lines: u64,
}

impl PcdHeader {
    /// Bytes of one binary record.
    pub fn record_bytes(&self) -> usize {
        self.fields.iter().map(Field::bytes).sum()
    }

    /// Index of the field called `name` holding one value, the name's
    /// case ignored (PDAL writes `X Y Z`, PCL `x y z`).
    pub fn scalar_field(&self, name: &str) -> Option<usize> {
        self.fields
            .iter()
            .position(|f| f.name.eq_ignore_ascii_case(name) && f.count == 1)
    }

    /// Whether the cloud is organised: rows of a sensor's pixel grid,
    /// where NaN coordinates mark a pixel without a return.
    pub fn organised(&self) -> bool {
        self.height > 1
    }

    /// Byte offset of field `i` within a binary record.
    pub fn offset(&self, i: usize) -> usize {
        self.fields[..i].iter().map(Field::bytes).sum()
    }

    /// Value index of field `i`'s first value within an ASCII line.
    pub fn column(&self, i: usize) -> usize {
        self.fields[..i].iter().map(|f| f.count).sum()
    }
}

/// Most fields accepted (PCL's own point types have fewer than 40).
const MAX_FIELDS: usize = 1024;

/// Reads the header up to and including its `DATA` line.
pub fn parse_header(input: &mut dyn BufRead) -> Result<PcdHeader, String> {
    let mut names: Vec<String> = Vec::new();
    let (mut sizes, mut types, mut counts) = (Vec::new(), Vec::new(), None);
    let (mut width, mut height, mut points) = (None, None, None);
    let mut lines = 0u64;
    let mut line = Vec::new();
    loop {
        let got = read_line(input, &mut line).map_err(|e| e.to_string())?;
        lines += 1;
        match got {
            Line::Eof => return Err("the header ends before its DATA line".into()),
            Line::TooLong => return Err(format!("header line {lines} is too long")),
            Line::Read | Line::Unterminated => {}
        }
        let text = as_text(&line).map_err(|e| format!("header line {lines}: {e}"))?;
        let mut words = text.split_ascii_whitespace();
        let Some(key) = words.next() else { continue };
        if key.starts_with('#') {
            continue;
        }
        let rest: Vec<&str> = words.collect();
        let bad = |what: &str| format!("line {lines}: bad {key} ({what})");
        match key.to_ascii_uppercase().as_str() {
            "VERSION" | "VIEWPOINT" => {}
            "FIELDS" | "COLUMNS" => {
                if rest.len() > MAX_FIELDS {
                    return Err(bad("too many fields"));
                }
                names = rest.iter().map(|s| s.to_string()).collect();
            }
            "SIZE" => sizes = numbers(&rest).ok_or_else(|| bad("not sizes"))?,
            "TYPE" => types = rest.iter().map(|s| s.to_string()).collect(),
            "COUNT" => counts = Some(numbers(&rest).ok_or_else(|| bad("not counts"))?),
            "WIDTH" => width = Some(number(&rest).ok_or_else(|| bad("not a count"))?),
            "HEIGHT" => height = Some(number(&rest).ok_or_else(|| bad("not a count"))?),
            "POINTS" => points = Some(number(&rest).ok_or_else(|| bad("not a count"))?),
            "DATA" => {
                let data = match rest.first().map(|s| s.to_ascii_lowercase()).as_deref() {
                    Some("ascii") => Data::Ascii,
                    Some("binary") => Data::Binary,
                    Some("binary_compressed") => Data::Compressed,
                    _ => return Err(bad("expected ascii, binary or binary_compressed")),
                };
                let fields = fields(&names, &sizes, &types, counts.as_deref())?;
                let points = point_count(width, height, points)?;
                // PCL's reader makes a cloud without WIDTH unorganised.
                let height = match (width, height) {
                    (Some(w), Some(h)) if w.checked_mul(h) == Some(points) => h,
                    _ => 1,
                };
                return Ok(PcdHeader {
                    fields,
                    points,
                    height,
                    data,
                    lines,
                });
            }
            _ => return Err(format!("line {lines}: unknown header keyword '{key}'")),
        }
    }
}

fn number(words: &[&str]) -> Option<u64> {
    match words {
        [w] => w.parse().ok(),
        _ => None,
    }
}

fn numbers(words: &[&str]) -> Option<Vec<u64>> {
    words.iter().map(|w| w.parse().ok()).collect()
}

fn fields(
    names: &[String],
    sizes: &[u64],
    types: &[String],
    counts: Option<&[u64]>,
) -> Result<Vec<Field>, String> {
    let n = names.len();
    if n == 0 {
        return Err("no FIELDS line".into());
    }
    if sizes.len() != n || types.len() != n || counts.is_some_and(|c| c.len() != n) {
        return Err(format!(
            "FIELDS names {n} fields but SIZE, TYPE or COUNT give another number"
        ));
    }
    (0..n)
        .map(|i| {
            let size = sizes[i] as usize;
            let scalar = match (types[i].as_str(), size) {
                ("F", 4 | 8) => Scalar::F(size),
                ("I", 1 | 2 | 4 | 8) => Scalar::I(size),
                ("U", 1 | 2 | 4 | 8) => Scalar::U(size),
                (t, s) => return Err(format!("field '{}': no type {t} of {s} bytes", names[i])),
            };
            let count = counts.map_or(1, |c| c[i]);
            if count == 0 || count > 1 << 16 {
                return Err(format!(
                    "field '{}': COUNT {count} is out of range",
                    names[i]
                ));
            }
            Ok(Field {
                name: names[i].clone(),
                scalar,
                count: count as usize,
            })
        })
        .collect()
}

/// POINTS, or WIDTH x HEIGHT when it is missing; the two must agree.
fn point_count(
    width: Option<u64>,
    height: Option<u64>,
    points: Option<u64>,
) -> Result<u64, String> {
    let grid = match (width, height) {
        (Some(w), Some(h)) => Some(
            w.checked_mul(h)
                .ok_or_else(|| "WIDTH x HEIGHT overflows".to_string())?,
        ),
        (Some(w), None) => Some(w),
        _ => None,
    };
    match (grid, points) {
        (Some(g), Some(p)) if g != p => {
            Err(format!("POINTS {p} disagrees with WIDTH x HEIGHT = {g}"))
        }
        (_, Some(p)) => Ok(p),
        (Some(g), None) => Ok(g),
        (None, None) => Err("neither POINTS nor WIDTH is given".into()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(s: &str) -> Result<PcdHeader, String> {
        parse_header(&mut s.as_bytes())
    }

    #[test]
    fn a_pcl_header_parses() {
        let h = parse(
            "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z rgb\n\
             SIZE 4 4 4 4\nTYPE F F F U\nCOUNT 1 1 1 1\nWIDTH 3\nHEIGHT 1\n\
             VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 3\nDATA binary\n",
        )
        .unwrap();
        assert_eq!(h.points, 3);
        assert_eq!(h.data, Data::Binary);
        assert_eq!(h.record_bytes(), 16);
        assert_eq!(h.scalar_field("z"), Some(2));
        assert_eq!(h.offset(3), 12);
        assert_eq!(h.fields[3].scalar, Scalar::U(4));
        assert!(!h.organised());
    }

    #[test]
    fn names_match_in_any_case_and_a_grid_is_organised() {
        let h = parse(
            "FIELDS X Y Z Intensity\nSIZE 8 8 8 4\nTYPE F F F F\n\
             WIDTH 4\nHEIGHT 3\nPOINTS 12\nDATA binary\n",
        )
        .unwrap();
        assert_eq!(
            ["x", "Y", "z", "intensity"].map(|n| h.scalar_field(n)),
            [Some(0), Some(1), Some(2), Some(3)]
        );
        assert!(h.organised());
        assert_eq!(h.height, 3);
    }

    #[test]
    fn inconsistent_headers_are_errors() {
        let base = "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\n";
        for (tail, want) in [
            ("WIDTH 4\nHEIGHT 1\nPOINTS 5\nDATA ascii\n", "disagrees"),
            ("DATA ascii\n", "neither POINTS"),
            ("POINTS 4\nDATA zip\n", "bad DATA"),
            ("POINTS 4\n", "before its DATA"),
            ("POINTS 99999999999999999999999\nDATA ascii\n", "bad POINTS"),
            (
                "WIDTH 18446744073709551615\nHEIGHT 2\nDATA ascii\n",
                "overflows",
            ),
            ("COUNT 1 1\nPOINTS 1\nDATA ascii\n", "another number"),
            ("COUNT 1 1 0\nPOINTS 1\nDATA ascii\n", "out of range"),
            ("FOO 1\nDATA ascii\n", "unknown header keyword"),
        ] {
            let err = parse(&format!("{base}{tail}")).unwrap_err();
            assert!(err.contains(want), "{tail:?}: {err}");
        }
        let err = parse("FIELDS x y z\nSIZE 4 4 3\nTYPE F F F\nPOINTS 1\nDATA ascii\n");
        assert!(err.unwrap_err().contains("no type F of 3 bytes"));
    }
}
