//! Binary PLY scalars and the fast path for vertex records of fixed size:
//! a whole block of records is read into one reused buffer and decoded in
//! place from byte offsets (no per-property `Read` calls).

use super::header::{Element, ScalarType};
use byteorder::ByteOrder;
use glam::{DVec3, Vec3};

/// Decodes one scalar from the start of `b` (which holds at least its size).
#[inline(always)]
pub(crate) fn decode<B: ByteOrder>(b: &[u8], t: ScalarType) -> f64 {
    match t {
        ScalarType::I8 => f64::from(b[0] as i8),
        ScalarType::U8 => f64::from(b[0]),
        ScalarType::I16 => f64::from(B::read_i16(b)),
        ScalarType::U16 => f64::from(B::read_u16(b)),
        ScalarType::I32 => f64::from(B::read_i32(b)),
        ScalarType::U32 => f64::from(B::read_u32(b)),
        ScalarType::F32 => f64::from(B::read_f32(b)),
        ScalarType::F64 => B::read_f64(b),
    }
}

#[inline(always)]
fn slot<B: ByteOrder>(rec: &[u8], s: Slot) -> f64 {
    decode::<B>(&rec[s.offset..], s.ty)
}

#[derive(Clone, Copy, Debug)]
struct Slot {
    offset: usize,
    ty: ScalarType,
}

/// Where x, y, z (and nx, ny, nz) sit in a fixed-size vertex record.
#[derive(Clone, Debug)]
pub(crate) struct FixedLayout {
    pub size: usize,
    xyz: [Slot; 3],
    normals: Option<[Slot; 3]>,
    /// Every property, for the attributes ([`FixedLayout::prop`]).
    props: Vec<Slot>,
}

impl FixedLayout {
    /// `None` when the element has list properties (records vary in size).
    /// `xyz` and `normals` are property indices into `element.props`.
    pub fn new(element: &Element, xyz: [usize; 3], normals: Option<[usize; 3]>) -> Option<Self> {
        let size = element.fixed_size()?;
        let mut props = Vec::with_capacity(element.props.len());
        let mut at = 0;
        for p in &element.props {
            let super::header::PropertyKind::Scalar(ty) = p.kind else {
                return None;
            };
            props.push(Slot { offset: at, ty });
            at += ty.size();
        }
        let slot = |i: usize| props[i];
        Some(FixedLayout {
            size,
            xyz: xyz.map(slot),
            normals: normals.map(|n| n.map(slot)),
            props,
        })
    }

    /// Position and normal (zero when the layout has none) of one record.
    #[inline(always)]
    pub fn decode<B: ByteOrder>(&self, rec: &[u8]) -> (DVec3, Vec3) {
        let [x, y, z] = self.xyz;
        let p = DVec3::new(slot::<B>(rec, x), slot::<B>(rec, y), slot::<B>(rec, z));
        let n = match self.normals {
            Some([a, b, c]) => Vec3::new(
                slot::<B>(rec, a) as f32,
                slot::<B>(rec, b) as f32,
                slot::<B>(rec, c) as f32,
            ),
            None => Vec3::ZERO,
        };
        (p, n)
    }

    /// Property `i` of one record.
    #[inline(always)]
    pub fn prop<B: ByteOrder>(&self, rec: &[u8], i: usize) -> f64 {
        slot::<B>(rec, self.props[i])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::ply::header::{Property, PropertyKind};
    use byteorder::{BigEndian, LittleEndian};

    #[test]
    fn decodes_every_type_both_orders() {
        let cases: [(ScalarType, f64); 8] = [
            (ScalarType::I8, -5.0),
            (ScalarType::U8, 200.0),
            (ScalarType::I16, -30000.0),
            (ScalarType::U16, 60000.0),
            (ScalarType::I32, -2_000_000_000.0),
            (ScalarType::U32, 4_000_000_000.0),
            (ScalarType::F32, 1.5),
            (ScalarType::F64, -1e300),
        ];
        for (t, v) in cases {
            let mut le = [0u8; 8];
            let mut be = [0u8; 8];
            match t {
                ScalarType::I8 => le[0] = (v as i8) as u8,
                ScalarType::U8 => le[0] = v as u8,
                ScalarType::I16 => LittleEndian::write_i16(&mut le, v as i16),
                ScalarType::U16 => LittleEndian::write_u16(&mut le, v as u16),
                ScalarType::I32 => LittleEndian::write_i32(&mut le, v as i32),
                ScalarType::U32 => LittleEndian::write_u32(&mut le, v as u32),
                ScalarType::F32 => LittleEndian::write_f32(&mut le, v as f32),
                ScalarType::F64 => LittleEndian::write_f64(&mut le, v),
            }
            be[..t.size()].copy_from_slice(&le[..t.size()]);
            be[..t.size()].reverse();
            assert_eq!(decode::<LittleEndian>(&le, t), v, "{t:?} LE");
            assert_eq!(decode::<BigEndian>(&be, t), v, "{t:?} BE");
        }
    }

    #[test]
    fn layout_offsets_follow_property_order() {
        let prop = |name: &str, t| Property {
            name: name.into(),
            kind: PropertyKind::Scalar(t),
        };
        let el = Element {
            name: "vertex".into(),
            count: 1,
            props: vec![
                prop("red", ScalarType::U8),
                prop("z", ScalarType::I16),
                prop("x", ScalarType::F64),
                prop("y", ScalarType::F32),
            ],
        };
        let l = FixedLayout::new(&el, [2, 3, 1], None).unwrap();
        assert_eq!(l.size, 1 + 2 + 8 + 4);
        let mut rec = vec![7u8];
        rec.extend_from_slice(&(-3i16).to_le_bytes());
        rec.extend_from_slice(&0.25f64.to_le_bytes());
        rec.extend_from_slice(&(-8.5f32).to_le_bytes());
        let (p, _) = l.decode::<LittleEndian>(&rec);
        assert_eq!(p, DVec3::new(0.25, -8.5, -3.0));
    }
}
