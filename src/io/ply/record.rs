//! One record of any PLY element in any encoding: the general path, used for
//! ASCII bodies, binary elements with list properties, and for elements that
//! are skipped (never decoded beyond what their layout requires).

use super::binary::decode;
use super::header::{Element, Encoding, PropertyKind, ScalarType};
use crate::io::source::{binary_tail, read_full, skip_bytes, Tail};
use crate::io::text::{self, Line};
use byteorder::{BigEndian, ByteOrder, LittleEndian};
use std::io::{self, BufRead};

#[derive(Debug)]
pub(crate) enum RecordError {
    /// The data ended before the record was complete (or began).
    Eof,
    Bad(String),
    Io(io::Error),
    /// The record is on the input's last line, which has no end of line
    /// (`line`): it may be cut inside its last number.
    Cut {
        line: u64,
    },
}

fn io_err(e: io::Error) -> RecordError {
    if e.kind() == io::ErrorKind::UnexpectedEof {
        RecordError::Eof
    } else {
        RecordError::Io(e)
    }
}

/// Decodes records of one element; scalar values land in `values` (by
/// property index, only those `wanted`), the items of list `keep_list` in
/// `list`.
pub(crate) struct RecordDecoder {
    encoding: Encoding,
    kinds: Vec<PropertyKind>,
    names: Vec<String>,
    wanted: Vec<bool>,
    keep_list: Option<usize>,
    pub values: Vec<f64>,
    pub list: Vec<f64>,
    line: Vec<u8>,
    /// Last line read, numbered as in the file (ASCII only).
    pub line_no: u64,
    /// The last line read is the input's last and has no end of line.
    unterminated: bool,
}

impl RecordDecoder {
    pub fn new(
        element: &Element,
        encoding: Encoding,
        wanted: &[usize],
        keep_list: Option<usize>,
        line_no: u64,
    ) -> Self {
        let n = element.props.len();
        let mut want = vec![false; n];
        for &i in wanted {
            want[i] = true;
        }
        RecordDecoder {
            encoding,
            kinds: element.props.iter().map(|p| p.kind).collect(),
            names: element.props.iter().map(|p| p.name.clone()).collect(),
            wanted: want,
            keep_list,
            values: vec![0.0; n],
            list: Vec::new(),
            line: Vec::new(),
            line_no,
            unterminated: false,
        }
    }

    pub fn read<R: BufRead + ?Sized>(&mut self, r: &mut R) -> Result<(), RecordError> {
        match self.encoding {
            Encoding::Ascii => self.read_ascii(r),
            Encoding::BinaryLe => self.read_binary::<LittleEndian, R>(r),
            Encoding::BinaryBe => self.read_binary::<BigEndian, R>(r),
        }
    }

    /// Reads the next non-blank line; `Ok(false)` at end of input.
    pub fn next_line<R: BufRead + ?Sized>(&mut self, r: &mut R) -> Result<bool, RecordError> {
        loop {
            let got = text::read_line(r, &mut self.line).map_err(io_err)?;
            if got == Line::Eof {
                return Ok(false);
            }
            self.line_no += 1;
            if got == Line::TooLong {
                let msg = format!("longer than {} bytes", text::MAX_LINE);
                return Err(RecordError::Bad(format!("line {}: {msg}", self.line_no)));
            }
            self.unterminated = got == Line::Unterminated;
            if !self.line.iter().all(u8::is_ascii_whitespace) {
                return Ok(true);
            }
        }
    }

    fn read_ascii<R: BufRead + ?Sized>(&mut self, r: &mut R) -> Result<(), RecordError> {
        if !self.next_line(r)? {
            return Err(RecordError::Eof);
        }
        let line_no = self.line_no;
        if self.unterminated {
            return Err(RecordError::Cut { line: line_no });
        }
        let at = |e: String| RecordError::Bad(format!("line {line_no}: {e}"));
        let s = text::as_text(&self.line).map_err(at)?;
        let mut tok = s.split_ascii_whitespace();
        for (i, kind) in self.kinds.iter().enumerate() {
            let name = &self.names[i];
            let missing = || at(format!("too few values (no '{name}')"));
            let t = tok.next().ok_or_else(missing)?;
            match kind {
                PropertyKind::Scalar(ty) if self.wanted[i] => {
                    self.values[i] = parse_typed(t, *ty, name).map_err(at)?;
                }
                PropertyKind::Scalar(_) => {}
                PropertyKind::List { item, .. } => {
                    let n = t.parse::<u64>().map_err(|_| {
                        at(format!("'{name}': bad list count '{}'", text::shorten(t)))
                    })?;
                    let keep = self.keep_list == Some(i);
                    if keep {
                        self.list.clear();
                    }
                    for _ in 0..n {
                        let t = tok.next().ok_or_else(missing)?;
                        if keep {
                            self.list.push(parse_typed(t, *item, name).map_err(at)?);
                        }
                    }
                }
            }
        }
        match tok.next() {
            Some(extra) => Err(at(format!(
                "unexpected value '{}' after the last property (trailing garbage)",
                text::shorten(extra)
            ))),
            None => Ok(()),
        }
    }

    fn read_binary<B: ByteOrder, R: BufRead + ?Sized>(
        &mut self,
        r: &mut R,
    ) -> Result<(), RecordError> {
        for i in 0..self.kinds.len() {
            match self.kinds[i] {
                PropertyKind::Scalar(t) => {
                    let v = read_scalar::<B, R>(r, t)?;
                    if self.wanted[i] {
                        self.values[i] = v;
                    }
                }
                PropertyKind::List { count, item } => {
                    let n = read_scalar::<B, R>(r, count)?;
                    if n < 0.0 {
                        let msg = format!("'{}': negative list count {n}", self.names[i]);
                        return Err(RecordError::Bad(msg));
                    }
                    self.read_list::<B, R>(r, i, n as u64, item)?;
                }
            }
        }
        Ok(())
    }

    fn read_list<B: ByteOrder, R: BufRead + ?Sized>(
        &mut self,
        r: &mut R,
        i: usize,
        n: u64,
        item: ScalarType,
    ) -> Result<(), RecordError> {
        if self.keep_list == Some(i) {
            self.list.clear();
            for _ in 0..n {
                self.list.push(read_scalar::<B, R>(r, item)?);
            }
            return Ok(());
        }
        // n < 2^32 (integer count types are at most 32 bits), so no overflow.
        let bytes = n * item.size() as u64;
        if skip_bytes(r, bytes).map_err(io_err)? < bytes {
            return Err(RecordError::Eof);
        }
        Ok(())
    }
}

/// A `float` property holds an f32: its text is parsed as f32 (then widened
/// exactly), so ASCII and binary encodings of a file give the same values.
fn parse_typed(tok: &str, ty: ScalarType, name: &str) -> Result<f64, String> {
    match ty {
        ScalarType::F32 => text::parse_f32(tok, name).map(f64::from),
        _ => text::parse_f64(tok, name),
    }
}

fn read_scalar<B: ByteOrder, R: BufRead + ?Sized>(
    r: &mut R,
    t: ScalarType,
) -> Result<f64, RecordError> {
    let mut b = [0u8; 8];
    let want = t.size();
    if read_full(r, &mut b[..want]).map_err(io_err)? < want {
        return Err(RecordError::Eof);
    }
    Ok(decode::<B>(&b, t))
}

/// Skips all records of `element`, returning the count found before an error.
pub(crate) fn skip_element<R: BufRead + ?Sized>(
    r: &mut R,
    element: &Element,
    encoding: Encoding,
    line_no: &mut u64,
) -> Result<(), (u64, RecordError)> {
    if let (Some(size), false) = (element.fixed_size(), encoding == Encoding::Ascii) {
        let size = size as u64;
        let Some(bytes) = element.count.checked_mul(size) else {
            let msg = format!("element '{}' is larger than any file", element.name);
            return Err((0, RecordError::Bad(msg)));
        };
        let got = skip_bytes(r, bytes).map_err(|e| (0, io_err(e)))?;
        return match got < bytes {
            true => Err((got / size.max(1), RecordError::Eof)),
            false => Ok(()),
        };
    }
    let mut dec = RecordDecoder::new(element, encoding, &[], None, *line_no);
    for k in 0..element.count {
        dec.read(r).map_err(|e| (k, e))?;
    }
    *line_no = dec.line_no;
    Ok(())
}

/// What follows the last declared element.
#[derive(Debug, PartialEq, Eq)]
pub(crate) enum Rest {
    /// The end of the input (or, binary, only zero bytes: padding).
    End,
    /// A line that is not blank, numbered as in the file (ASCII).
    Line(u64),
    /// Bytes that are not all zero (binary).
    Bytes(Tail),
}

/// Reads what follows the last declared element; `line_no` is the number
/// of the last line read (ASCII).
pub(crate) fn rest<R: BufRead + ?Sized>(
    r: &mut R,
    encoding: Encoding,
    mut line_no: u64,
) -> io::Result<Rest> {
    if encoding != Encoding::Ascii {
        return Ok(binary_tail(r)?.map_or(Rest::End, Rest::Bytes));
    }
    let mut line = Vec::new();
    loop {
        let got = text::read_line(r, &mut line)?;
        if got == Line::Eof {
            return Ok(Rest::End);
        }
        line_no += 1;
        if got == Line::TooLong || !line.iter().all(u8::is_ascii_whitespace) {
            return Ok(Rest::Line(line_no));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::ply::header::parse_header;

    #[test]
    fn ascii_record_with_list_and_trailing_garbage() {
        let src = "ply\nformat ascii 1.0\nelement vertex 2\nproperty list uchar int l\n\
                   property float x\nend_header\n3 1 2 3 0.5\n\n1 9 0.25 extra\n";
        let mut r = src.as_bytes();
        let h = parse_header(&mut r).unwrap();
        let mut d = RecordDecoder::new(&h.elements[0], h.encoding, &[1], Some(0), h.lines);
        d.read(&mut r).unwrap();
        assert_eq!((d.values[1], d.list.clone()), (0.5, vec![1.0, 2.0, 3.0]));
        match d.read(&mut r) {
            Err(RecordError::Bad(m)) => assert!(m.contains("line 9") && m.contains("extra"), "{m}"),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn the_rest_after_the_last_element() {
        let rest_of = |body: &[u8], enc| rest(&mut &body[..], enc, 10).unwrap();
        assert_eq!(rest_of(b"", Encoding::Ascii), Rest::End);
        assert_eq!(rest_of(b"\n  \r\n\t", Encoding::Ascii), Rest::End);
        assert_eq!(rest_of(b"\n\n1 2 3\n", Encoding::Ascii), Rest::Line(13));
        assert_eq!(rest_of(&[0; 300], Encoding::BinaryLe), Rest::End);
        let tail = Tail {
            bytes: 3,
            exact: true,
        };
        assert_eq!(rest_of(&[0, 0, 9], Encoding::BinaryBe), Rest::Bytes(tail));
    }

    #[test]
    fn ascii_record_on_a_last_line_without_end_of_line_is_cut() {
        let src = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nend_header\n1\n2.5";
        let mut r = src.as_bytes();
        let h = parse_header(&mut r).unwrap();
        let mut d = RecordDecoder::new(&h.elements[0], h.encoding, &[0], None, h.lines);
        d.read(&mut r).unwrap();
        assert!(matches!(d.read(&mut r), Err(RecordError::Cut { line: 7 })));
    }

    #[test]
    fn binary_skip_reports_found_records() {
        let src =
            b"ply\nformat binary_little_endian 1.0\nelement cam 5\nproperty int a\nend_header\n\
                    \x01\x00\x00\x00\x02\x00\x00\x00\x03\x00";
        let mut r = &src[..];
        let h = parse_header(&mut r).unwrap();
        let mut line = h.lines;
        match skip_element(&mut r, &h.elements[0], h.encoding, &mut line) {
            Err((2, RecordError::Eof)) => {}
            other => panic!("{other:?}"),
        }
    }
}
