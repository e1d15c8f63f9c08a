//! Per-point attributes scanners record besides positions (intensity, RGB
//! colour, classification, return number, GPS time): their types, the set a
//! source carries or a writer writes, and a chunk's columns of them.
//!
//! One representation serves every format, so a value survives any pair of
//! formats that can hold it (README "Attributes"): intensity as u16 (LAS),
//! colour as three u16 (LAS, E57; 8-bit sources are widened by x257, so
//! 255 becomes 65535 and narrowing back by `>> 8` is exact), classification
//! and return number as u8 (LAS), GPS time as f64 seconds.

use serde::{Deserialize, Serialize};

/// One kind of per-point attribute.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Attribute {
    /// Return intensity (u16, as in LAS).
    Intensity,
    /// Colour as red, green, blue (u16 each; 8-bit sources widened by x257).
    Rgb,
    /// Classification code (u8, as in LAS).
    Classification,
    /// Return number of a multi-return pulse (u8).
    ReturnNumber,
    /// GPS time of the pulse (f64 seconds).
    GpsTime,
}

impl Attribute {
    /// Every kind, in the order files and columns list them.
    pub const ALL: [Attribute; 5] = [
        Attribute::Intensity,
        Attribute::Rgb,
        Attribute::Classification,
        Attribute::ReturnNumber,
        Attribute::GpsTime,
    ];

    /// The name used in messages, the manifest and `info`.
    pub fn name(self) -> &'static str {
        match self {
            Attribute::Intensity => "intensity",
            Attribute::Rgb => "rgb",
            Attribute::Classification => "classification",
            Attribute::ReturnNumber => "return_number",
            Attribute::GpsTime => "gps_time",
        }
    }

    /// Bytes of one value, little-endian, in a store column.
    pub fn item_bytes(self) -> usize {
        match self {
            Attribute::Intensity => 2,
            Attribute::Rgb => 6,
            Attribute::Classification | Attribute::ReturnNumber => 1,
            Attribute::GpsTime => 8,
        }
    }

    fn bit(self) -> u8 {
        1 << (self as u8)
    }
}

/// A set of attribute kinds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct AttributeSet(u8);

impl AttributeSet {
    /// No attribute.
    pub const EMPTY: AttributeSet = AttributeSet(0);

    /// The set of the kinds in `attrs`.
    pub fn of(attrs: &[Attribute]) -> Self {
        AttributeSet(attrs.iter().fold(0, |m, a| m | a.bit()))
    }

    /// Every kind of [`Attribute::ALL`].
    pub fn all() -> Self {
        Self::of(&Attribute::ALL)
    }

    /// Whether `a` is in the set.
    pub fn contains(self, a: Attribute) -> bool {
        self.0 & a.bit() != 0
    }

    /// The set plus `a`.
    pub fn with(self, a: Attribute) -> Self {
        AttributeSet(self.0 | a.bit())
    }

    /// Whether the set has no attribute.
    pub fn is_empty(self) -> bool {
        self.0 == 0
    }

    /// Those of `self` that are also in `other`.
    pub fn intersect(self, other: AttributeSet) -> Self {
        AttributeSet(self.0 & other.0)
    }

    /// Those of `self` that are not in `other`.
    pub fn without(self, other: AttributeSet) -> Self {
        AttributeSet(self.0 & !other.0)
    }

    /// The kinds in the set, in the order of [`Attribute::ALL`].
    pub fn iter(self) -> impl Iterator<Item = Attribute> {
        Attribute::ALL
            .into_iter()
            .filter(move |a| self.contains(*a))
    }

    /// The kinds in the set as a vector, in the order of [`Attribute::ALL`].
    pub fn to_vec(self) -> Vec<Attribute> {
        self.iter().collect()
    }

    /// The names, comma-separated ("none" when empty).
    pub fn describe(self) -> String {
        match self.is_empty() {
            true => "none".into(),
            false => self
                .iter()
                .map(Attribute::name)
                .collect::<Vec<_>>()
                .join(", "),
        }
    }

    /// Bytes of one point's values of every attribute in the set.
    pub fn bytes_per_point(self) -> usize {
        self.iter().map(Attribute::item_bytes).sum()
    }
}

/// One point's attribute values (those outside a set are ignored).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AttributeValues {
    /// Return intensity.
    pub intensity: u16,
    /// Red, green, blue, 16 bits each.
    pub rgb: [u16; 3],
    /// Classification code.
    pub classification: u8,
    /// Return number.
    pub return_number: u8,
    /// GPS time in seconds.
    pub gps_time: f64,
}

/// The largest value of some attributes over a set of points: what a LAS
/// output needs before its first point (the point format that holds the
/// classes and return numbers) and what tells 8-bit colour stored in
/// 16-bit fields (every channel at most 255) from 16-bit colour.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct AttributeMaxima {
    /// Largest colour channel (0 without colour).
    pub rgb: u16,
    /// Largest classification code.
    pub classification: u8,
    /// Largest return number.
    pub return_number: u8,
}

impl AttributeMaxima {
    /// Takes in the values of `a`'s points.
    pub fn add(&mut self, a: &Attributes) {
        let max_u8 = |v: &[u8]| v.iter().copied().max().unwrap_or(0);
        let rgb = a.rgb.iter().flatten().copied().max().unwrap_or(0);
        self.rgb = self.rgb.max(rgb);
        self.classification = self.classification.max(max_u8(&a.classification));
        self.return_number = self.return_number.max(max_u8(&a.return_number));
    }

    /// Whether every colour channel is at most 255: 8-bit colour in
    /// 16-bit fields, as many LAS files hold it (the rule PDAL's and
    /// CloudCompare's readers apply, per file).
    pub fn eight_bit_colour(&self) -> bool {
        self.rgb <= 255
    }
}

/// Widens an 8-bit colour channel to 16 bits (0 -> 0, 255 -> 65535).
pub fn widen_8bit(v: u8) -> u16 {
    u16::from(v) * 257
}

/// Narrows a 16-bit colour channel to 8 bits (exact for widened values).
pub fn narrow_16bit(v: u16) -> u8 {
    (v >> 8) as u8
}

/// Rounds `v` into `0..=max`: for formats that store attributes as floats.
pub fn to_unsigned(v: f64, max: u16) -> u16 {
    match v.is_nan() {
        true => 0,
        false => v.round().clamp(0.0, f64::from(max)) as u16,
    }
}

/// A chunk's attribute columns: for each attribute of [`Attributes::set`],
/// one value per point; the others are empty.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Attributes {
    set: AttributeSet,
    /// Intensities, one per point when the set has [`Attribute::Intensity`].
    pub intensity: Vec<u16>,
    /// Colours (red, green, blue), one per point when the set has [`Attribute::Rgb`].
    pub rgb: Vec<[u16; 3]>,
    /// Classification codes, one per point when the set has [`Attribute::Classification`].
    pub classification: Vec<u8>,
    /// Return numbers, one per point when the set has [`Attribute::ReturnNumber`].
    pub return_number: Vec<u8>,
    /// GPS times in seconds, one per point when the set has [`Attribute::GpsTime`].
    pub gps_time: Vec<f64>,
    /// The input's own LAS point records, one per point, when the input
    /// is LAS/LAZ (else empty): what a LAS output of it writes.
    pub las: LasRecords,
}

/// LAS point records byte for byte (every standard field and the extra
/// bytes), `record_len` bytes each: a LAS input's points as its file holds
/// them, so that a LAS output keeps every field, not only the attributes
/// scanmesh knows by name.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LasRecords {
    /// Bytes of one record (the input's point data record length).
    pub record_len: usize,
    /// The records, `record_len` bytes a point.
    pub bytes: Vec<u8>,
}

impl LasRecords {
    /// Records held.
    pub fn len(&self) -> usize {
        self.bytes.len().checked_div(self.record_len).unwrap_or(0)
    }

    /// Whether no record is held.
    pub fn is_empty(&self) -> bool {
        self.bytes.is_empty()
    }

    /// Record `i`.
    pub fn get(&self, i: usize) -> &[u8] {
        &self.bytes[i * self.record_len..(i + 1) * self.record_len]
    }

    /// Record `i`, when one is held for every one of `points` points.
    pub fn record(&self, i: usize, points: usize) -> Option<&[u8]> {
        (self.record_len > 0 && self.len() == points).then(|| self.get(i))
    }

    /// Appends `record` (its length sets the records').
    pub fn push(&mut self, record: &[u8]) {
        self.record_len = record.len();
        self.bytes.extend_from_slice(record);
    }

    /// Keeps the records whose `keep` is true, in order; records not
    /// held for every point of `keep` stay as they are.
    pub(crate) fn retain(&mut self, keep: &[bool]) {
        let len = self.record_len;
        if len == 0 || self.len() != keep.len() || self.bytes.len() != len * keep.len() {
            return;
        }
        let mut kept = 0;
        for (i, _) in keep.iter().enumerate().filter(|(_, &k)| k) {
            self.bytes.copy_within(i * len..(i + 1) * len, kept * len);
            kept += 1;
        }
        self.bytes.truncate(kept * len);
    }
}

impl Attributes {
    /// Empties the columns (keeping their allocations) for points carrying
    /// the attributes of `set`.
    pub fn reset(&mut self, set: AttributeSet) {
        self.set = set;
        self.clear();
    }

    /// Empties every column, keeping the set and the allocations.
    pub fn clear(&mut self) {
        self.intensity.clear();
        self.rgb.clear();
        self.classification.clear();
        self.return_number.clear();
        self.gps_time.clear();
        self.las.bytes.clear();
    }

    /// Widens 8-bit colour held in 16-bit fields (a LAS file whose every
    /// channel is at most 255, [`AttributeMaxima::eight_bit_colour`]) to
    /// true 16-bit values, so that every writer narrows or keeps it as it
    /// does any 16-bit colour.
    pub fn widen_8bit_colour(&mut self) {
        for c in self.rgb.iter_mut().flatten() {
            *c = widen_8bit(*c as u8);
        }
    }

    /// The attributes the columns hold.
    pub fn set(&self) -> AttributeSet {
        self.set
    }

    /// Appends one point's values of the set's attributes.
    #[inline]
    pub fn push(&mut self, v: &AttributeValues) {
        if self.set.is_empty() {
            return;
        }
        let s = self.set;
        if s.contains(Attribute::Intensity) {
            self.intensity.push(v.intensity);
        }
        if s.contains(Attribute::Rgb) {
            self.rgb.push(v.rgb);
        }
        if s.contains(Attribute::Classification) {
            self.classification.push(v.classification);
        }
        if s.contains(Attribute::ReturnNumber) {
            self.return_number.push(v.return_number);
        }
        if s.contains(Attribute::GpsTime) {
            self.gps_time.push(v.gps_time);
        }
    }

    /// Appends the values of the set's attributes of `other`'s points
    /// `range` (`other` holds them), and when `records` their LAS records.
    pub fn extend_from(
        &mut self,
        other: &Attributes,
        range: std::ops::Range<usize>,
        records: bool,
    ) {
        let s = self.set;
        let r = range.clone();
        if s.contains(Attribute::Intensity) {
            self.intensity
                .extend_from_slice(&other.intensity[r.clone()]);
        }
        if s.contains(Attribute::Rgb) {
            self.rgb.extend_from_slice(&other.rgb[r.clone()]);
        }
        if s.contains(Attribute::Classification) {
            self.classification
                .extend_from_slice(&other.classification[r.clone()]);
        }
        if s.contains(Attribute::ReturnNumber) {
            self.return_number
                .extend_from_slice(&other.return_number[r.clone()]);
        }
        if s.contains(Attribute::GpsTime) {
            self.gps_time.extend_from_slice(&other.gps_time[r]);
        }
        if records {
            let len = other.las.record_len;
            self.las.record_len = len;
            self.las
                .bytes
                .extend_from_slice(&other.las.bytes[range.start * len..range.end * len]);
        }
    }

    /// Point `i`'s values (zero for attributes outside the set).
    #[inline]
    pub fn get(&self, i: usize) -> AttributeValues {
        let s = self.set;
        let pick = |yes: bool| yes.then_some(i);
        AttributeValues {
            intensity: pick(s.contains(Attribute::Intensity)).map_or(0, |i| self.intensity[i]),
            rgb: pick(s.contains(Attribute::Rgb)).map_or([0; 3], |i| self.rgb[i]),
            classification: pick(s.contains(Attribute::Classification))
                .map_or(0, |i| self.classification[i]),
            return_number: pick(s.contains(Attribute::ReturnNumber))
                .map_or(0, |i| self.return_number[i]),
            gps_time: pick(s.contains(Attribute::GpsTime)).map_or(0.0, |i| self.gps_time[i]),
        }
    }

    /// Values held for `a` (0 when `a` is not in the set).
    pub fn len_of(&self, a: Attribute) -> usize {
        match a {
            Attribute::Intensity => self.intensity.len(),
            Attribute::Rgb => self.rgb.len(),
            Attribute::Classification => self.classification.len(),
            Attribute::ReturnNumber => self.return_number.len(),
            Attribute::GpsTime => self.gps_time.len(),
        }
    }

    /// Appends the little-endian bytes of `a`'s values (as a store column
    /// holds them).
    pub fn encode_le(&self, a: Attribute, out: &mut Vec<u8>) {
        match a {
            Attribute::Intensity => self
                .intensity
                .iter()
                .for_each(|v| out.extend_from_slice(&v.to_le_bytes())),
            Attribute::Rgb => self
                .rgb
                .iter()
                .flatten()
                .for_each(|v| out.extend_from_slice(&v.to_le_bytes())),
            Attribute::Classification => out.extend_from_slice(&self.classification),
            Attribute::ReturnNumber => out.extend_from_slice(&self.return_number),
            Attribute::GpsTime => self
                .gps_time
                .iter()
                .for_each(|v| out.extend_from_slice(&v.to_le_bytes())),
        }
    }

    /// Appends `a`'s values decoded from little-endian `bytes` (whole items).
    pub fn decode_le(&mut self, a: Attribute, bytes: &[u8]) {
        let u16_at = |c: &[u8], k: usize| u16::from_le_bytes([c[2 * k], c[2 * k + 1]]);
        match a {
            Attribute::Intensity => self
                .intensity
                .extend(bytes.chunks_exact(2).map(|c| u16_at(c, 0))),
            Attribute::Rgb => self.rgb.extend(
                bytes
                    .chunks_exact(6)
                    .map(|c| [u16_at(c, 0), u16_at(c, 1), u16_at(c, 2)]),
            ),
            Attribute::Classification => self.classification.extend_from_slice(bytes),
            Attribute::ReturnNumber => self.return_number.extend_from_slice(bytes),
            Attribute::GpsTime => self.gps_time.extend(
                bytes
                    .chunks_exact(8)
                    .map(|c| f64::from_le_bytes([c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]])),
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(k: u16) -> AttributeValues {
        AttributeValues {
            intensity: 1000 + k,
            rgb: [k, 65535 - k, 257 * (k % 256)],
            classification: (k % 32) as u8,
            return_number: (k % 5) as u8 + 1,
            gps_time: 1.5e8 + f64::from(k) * 1e-6,
        }
    }

    #[test]
    fn le_columns_round_trip_every_attribute() {
        let mut a = Attributes::default();
        a.reset(AttributeSet::all());
        (0..100).for_each(|k| a.push(&sample(k)));
        let mut b = Attributes::default();
        b.reset(AttributeSet::all());
        for attr in Attribute::ALL {
            let mut bytes = Vec::new();
            a.encode_le(attr, &mut bytes);
            assert_eq!(bytes.len(), 100 * attr.item_bytes(), "{attr:?}");
            b.decode_le(attr, &bytes);
        }
        assert_eq!(a, b);
        assert_eq!(b.get(7), sample(7));
    }

    #[test]
    fn a_set_keeps_only_its_attributes() {
        let set = AttributeSet::of(&[Attribute::Rgb, Attribute::GpsTime]);
        let mut a = Attributes::default();
        a.reset(set);
        a.push(&sample(3));
        assert_eq!(
            (a.intensity.len(), a.rgb.len(), a.gps_time.len()),
            (0, 1, 1)
        );
        let got = a.get(0);
        assert_eq!(
            (got.intensity, got.rgb, got.gps_time),
            (0, sample(3).rgb, sample(3).gps_time)
        );
        assert_eq!(set.describe(), "rgb, gps_time");
        assert_eq!(set.bytes_per_point(), 14);
        assert_eq!(
            set.without(AttributeSet::of(&[Attribute::Rgb])).to_vec(),
            [Attribute::GpsTime]
        );
    }

    #[test]
    fn eight_bit_colour_survives_widening() {
        for v in 0..=255u8 {
            assert_eq!(narrow_16bit(widen_8bit(v)), v);
        }
        assert_eq!(widen_8bit(255), 65535);
        assert_eq!(to_unsigned(f64::NAN, 255), 0);
        assert_eq!(to_unsigned(300.4, 255), 255);
        assert_eq!(to_unsigned(-3.0, 255), 0);
    }
}
