//! Which vertex properties of a PLY file hold point attributes, under the
//! names writers use: ours and PDAL's (`intensity`, `red`, `classification`,
//! `return_number`, `gps_time`), CloudCompare's scalar fields
//! (`scalar_Intensity`, `scalar_GpsTime`, ...), and `diffuse_red` etc. for
//! colour.

use super::header::{Element, ScalarType};
use crate::io::attributes::{to_unsigned, widen_8bit};
use crate::io::{Attribute, AttributeSet, AttributeValues};

/// A property: its index in the element and its type.
type Prop = (usize, ScalarType);

/// The vertex properties that carry attributes.
#[derive(Clone, Debug, Default)]
pub(crate) struct AttrProps {
    intensity: Option<Prop>,
    rgb: Option<[Prop; 3]>,
    classification: Option<Prop>,
    return_number: Option<Prop>,
    gps_time: Option<Prop>,
}

/// A property name folded for matching: lower case, without CloudCompare's
/// `scalar_` prefix and without underscores.
fn fold(name: &str) -> String {
    let lower = name.to_ascii_lowercase();
    let bare = lower.strip_prefix("scalar_").unwrap_or(&lower);
    bare.replace('_', "")
}

impl AttrProps {
    pub fn find(vertex: &Element) -> Self {
        let scalar = |names: &[&str]| {
            vertex.props.iter().enumerate().find_map(|(i, p)| {
                let t = match p.kind {
                    super::header::PropertyKind::Scalar(t) => t,
                    _ => return None,
                };
                names.contains(&fold(&p.name).as_str()).then_some((i, t))
            })
        };
        let channel = |c: &str| scalar(&[c, &format!("diffuse{c}")]);
        let rgb = match [channel("red"), channel("green"), channel("blue")] {
            [Some(r), Some(g), Some(b)] => Some([r, g, b]),
            _ => None,
        };
        AttrProps {
            intensity: scalar(&["intensity"]),
            rgb,
            classification: scalar(&["classification"]),
            return_number: scalar(&["returnnumber"]),
            gps_time: scalar(&["gpstime"]),
        }
    }

    pub fn set(&self) -> AttributeSet {
        let mut s = AttributeSet::EMPTY;
        let mut add = |present: bool, a| {
            if present {
                s = s.with(a);
            }
        };
        add(self.intensity.is_some(), Attribute::Intensity);
        add(self.rgb.is_some(), Attribute::Rgb);
        add(self.classification.is_some(), Attribute::Classification);
        add(self.return_number.is_some(), Attribute::ReturnNumber);
        add(self.gps_time.is_some(), Attribute::GpsTime);
        s
    }

    /// Property indices to decode on the per-record path.
    pub fn indices(&self) -> Vec<usize> {
        let mut v: Vec<usize> = [self.intensity, self.classification]
            .into_iter()
            .chain([self.return_number, self.gps_time])
            .flatten()
            .map(|p| p.0)
            .collect();
        v.extend(self.rgb.iter().flatten().map(|p| p.0));
        v
    }

    /// The values of one record, `value(i)` giving property `i` as f64.
    #[inline]
    pub fn values(&self, value: impl Fn(usize) -> f64) -> AttributeValues {
        let int = |p: Option<Prop>, max: u16| p.map_or(0, |(i, _)| to_unsigned(value(i), max));
        let colour = |(i, t): Prop| match t {
            ScalarType::U8 => widen_8bit(value(i) as u8),
            _ => to_unsigned(value(i), u16::MAX),
        };
        AttributeValues {
            intensity: int(self.intensity, u16::MAX),
            rgb: self.rgb.map_or([0; 3], |c| c.map(colour)),
            classification: int(self.classification, 255) as u8,
            return_number: int(self.return_number, 255) as u8,
            gps_time: self.gps_time.map_or(0.0, |(i, _)| value(i)),
        }
    }
}
