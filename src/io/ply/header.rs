//! PLY header parsing (Turk's PLY format, as documented with the Stanford
//! 3-D Scanning Repository): `ply`, `format`, `comment`/`obj_info`, `element`
//! and `property` lines up to `end_header`, elements in any order.
//!
//! Counts are taken as declared and never used to size an allocation; the
//! readers check them against the data.

use std::io::{BufRead, Read};

use crate::io::text;

/// Longest header accepted: a file without `end_header` in its first bytes is
/// not PLY, and must not be read to the end looking for one.
const MAX_HEADER_BYTES: u64 = 1 << 20;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Encoding {
    Ascii,
    BinaryLe,
    BinaryBe,
}

/// The scalar types of PLY, under both their old and their sized names.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ScalarType {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl ScalarType {
    pub fn parse(name: &str) -> Option<ScalarType> {
        Some(match name {
            "char" | "int8" => ScalarType::I8,
            "uchar" | "uint8" => ScalarType::U8,
            "short" | "int16" => ScalarType::I16,
            "ushort" | "uint16" => ScalarType::U16,
            "int" | "int32" => ScalarType::I32,
            "uint" | "uint32" => ScalarType::U32,
            "float" | "float32" => ScalarType::F32,
            "double" | "float64" => ScalarType::F64,
            _ => return None,
        })
    }

    /// Bytes in the binary encodings.
    pub fn size(self) -> usize {
        match self {
            ScalarType::I8 | ScalarType::U8 => 1,
            ScalarType::I16 | ScalarType::U16 => 2,
            ScalarType::I32 | ScalarType::U32 | ScalarType::F32 => 4,
            ScalarType::F64 => 8,
        }
    }

    pub fn is_integer(self) -> bool {
        !matches!(self, ScalarType::F32 | ScalarType::F64)
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PropertyKind {
    Scalar(ScalarType),
    /// A count of type `count`, then that many items of type `item`.
    List {
        count: ScalarType,
        item: ScalarType,
    },
}

#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Property {
    pub name: String,
    pub kind: PropertyKind,
}

#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Element {
    pub name: String,
    pub count: u64,
    pub props: Vec<Property>,
}

impl Element {
    /// Index of the scalar property `name`.
    pub fn scalar(&self, name: &str) -> Option<(usize, ScalarType)> {
        self.props
            .iter()
            .enumerate()
            .find_map(|(i, p)| match p.kind {
                PropertyKind::Scalar(t) if p.name == name => Some((i, t)),
                _ => None,
            })
    }

    /// Record size in bytes when every property is a scalar.
    pub fn fixed_size(&self) -> Option<usize> {
        self.props.iter().try_fold(0usize, |acc, p| match p.kind {
            PropertyKind::Scalar(t) => Some(acc + t.size()),
            PropertyKind::List { .. } => None,
        })
    }
}

#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PlyHeader {
    pub encoding: Encoding,
    pub elements: Vec<Element>,
    /// Lines in the header, `end_header` included, so ASCII data lines can be
    /// numbered as in the file.
    pub lines: u64,
}

impl PlyHeader {
    pub fn element_index(&self, name: &str) -> Option<usize> {
        self.elements.iter().position(|e| e.name == name)
    }
}

/// Header errors carry only the reason; the caller adds the path.
pub type HeaderError = String;

/// Reads the header; `r` is left at the first byte of the body.
pub fn parse_header<R: BufRead + ?Sized>(r: &mut R) -> Result<PlyHeader, HeaderError> {
    let mut limited = Read::take(&mut *r, MAX_HEADER_BYTES);
    let mut buf = Vec::new();
    let mut lines = 0u64;
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    loop {
        let line = text::read_line(&mut limited, &mut buf).map_err(|e| e.to_string())?;
        // A header ends at `end_header`; its own line may end the file.
        if !line.is_line() {
            return Err("no 'end_header' line: not a PLY file, or its header is cut off".into());
        }
        lines += 1;
        let s = text::as_text(&buf).map_err(|e| format!("line {lines}: {e}"))?;
        let mut tok = s.split_ascii_whitespace();
        let keyword = tok.next().unwrap_or("");
        let at = |e: String| format!("line {lines}: {e}");
        match (lines, keyword) {
            (1, "ply") => continue,
            (1, _) => return Err("first line is not 'ply'".into()),
            (_, "end_header") => break,
            (_, "" | "comment" | "obj_info") => continue,
            (_, "format") => encoding = Some(parse_format(tok).map_err(at)?),
            (_, "element") => elements.push(parse_element(tok).map_err(at)?),
            (_, "property") => {
                let el = elements
                    .last_mut()
                    .ok_or_else(|| at("'property' before any 'element'".into()))?;
                el.props.push(parse_property(tok).map_err(at)?);
            }
            (_, other) => return Err(at(format!("unknown keyword '{}'", text::shorten(other)))),
        }
    }
    let encoding = encoding.ok_or("no 'format' line")?;
    Ok(PlyHeader {
        encoding,
        elements,
        lines,
    })
}

fn parse_format<'a>(mut tok: impl Iterator<Item = &'a str>) -> Result<Encoding, String> {
    let enc = match tok.next() {
        Some("ascii") => Encoding::Ascii,
        Some("binary_little_endian") => Encoding::BinaryLe,
        Some("binary_big_endian") => Encoding::BinaryBe,
        other => return Err(format!("unknown format {:?}", other.unwrap_or(""))),
    };
    match tok.next() {
        Some(v) if v.starts_with('1') => Ok(enc),
        v => Err(format!("unsupported PLY version {:?}", v.unwrap_or(""))),
    }
}

fn parse_element<'a>(mut tok: impl Iterator<Item = &'a str>) -> Result<Element, String> {
    let name = tok.next().ok_or("'element' without a name")?;
    let count = tok.next().ok_or("'element' without a count")?;
    let count = count
        .parse::<u64>()
        .map_err(|_| format!("element '{name}': bad count '{}'", text::shorten(count)))?;
    Ok(Element {
        name: name.to_string(),
        count,
        props: Vec::new(),
    })
}

fn parse_property<'a>(mut tok: impl Iterator<Item = &'a str>) -> Result<Property, String> {
    let scalar = |t: Option<&str>| {
        let t = t.ok_or("'property' without a type")?;
        ScalarType::parse(t).ok_or_else(|| format!("unknown property type '{}'", text::shorten(t)))
    };
    let first = tok.next();
    let kind = if first == Some("list") {
        let count = scalar(tok.next())?;
        if !count.is_integer() {
            return Err("list count type must be an integer type".into());
        }
        PropertyKind::List {
            count,
            item: scalar(tok.next())?,
        }
    } else {
        PropertyKind::Scalar(scalar(first)?)
    };
    let name = tok.next().ok_or("'property' without a name")?;
    Ok(Property {
        name: name.to_string(),
        kind,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_odd_header() {
        let h = "ply\r\nformat binary_big_endian 1.0\ncomment hi\nobj_info x\n\
                 element cam 1\nproperty list uint8 float32 v\n\
                 element vertex 3\nproperty uchar r\nproperty double x\n\
                 property float y\nproperty int z\nend_header\nBODY";
        let mut r = h.as_bytes();
        let hd = parse_header(&mut r).unwrap();
        assert_eq!(hd.encoding, Encoding::BinaryBe);
        assert_eq!(hd.lines, 12);
        assert_eq!(hd.elements.len(), 2);
        let v = &hd.elements[1];
        assert_eq!(v.count, 3);
        assert_eq!(v.scalar("x"), Some((1, ScalarType::F64)));
        assert_eq!(v.fixed_size(), Some(1 + 8 + 4 + 4));
        assert_eq!(hd.elements[0].fixed_size(), None);
        assert_eq!(r, b"BODY");
    }

    #[test]
    fn rejects_bad_type_and_missing_end() {
        let bad = "ply\nformat ascii 1.0\nelement vertex 1\nproperty quad x\nend_header\n";
        let e = parse_header(&mut bad.as_bytes()).unwrap_err();
        assert!(e.contains("quad"), "{e}");
        let cut = "ply\nformat ascii 1.0\nelement vertex 1\n";
        assert!(parse_header(&mut cut.as_bytes()).is_err());
        let no_fmt = "ply\nelement vertex 1\nproperty float x\nend_header\n";
        assert!(parse_header(&mut no_fmt.as_bytes()).is_err());
    }
}
