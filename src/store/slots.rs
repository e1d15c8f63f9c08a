//! What the export places for each point: the computed columns the output
//! carries ([`Columns`]: normals, values, flags) and the output slots of a range of
//! consecutive input ids they fill ([`Slots`]). The export's window passes
//! and the reorder's buckets both fill them, so they live below both.

use super::{Column, StoreError, TileEntry};
use glam::Vec3;

/// The computed columns the output carries.
pub(super) struct Columns {
    pub(super) normals: Option<Column>,
    /// `per_point` f32 values a point.
    pub(super) values: Option<Column>,
    pub(super) per_point: usize,
    pub(super) flags: Option<Column>,
}

/// One tile's computed columns, read.
#[derive(Default)]
pub(super) struct TileValues {
    pub(super) normals: Vec<f32>,
    pub(super) values: Vec<f32>,
    pub(super) flags: Vec<u8>,
}

impl TileValues {
    /// Point `k`'s normal (zero when not carried), values (`per` of them,
    /// none when not carried) and flags (0 when not carried).
    pub(super) fn of(&self, k: usize, per: usize) -> ([f32; 3], &[f32], u8) {
        let normal = match self.normals.get(3 * k..3 * k + 3) {
            Some(n) => [n[0], n[1], n[2]],
            None => [0.0; 3],
        };
        let values = self.values.get(per * k..per * (k + 1)).unwrap_or(&[]);
        (normal, values, self.flags.get(k).copied().unwrap_or(0))
    }
}

impl Columns {
    /// Whether the output carries a computed column (else nothing is placed).
    pub(super) fn any(&self) -> bool {
        self.normals.is_some() || self.values.is_some() || self.flags.is_some()
    }

    /// Reads tile `t`'s computed columns, those the output carries.
    pub(super) fn read(&self, t: &TileEntry, into: &mut TileValues) -> Result<(), StoreError> {
        if let Some(c) = &self.normals {
            c.read_f32(t.start, t.count, &mut into.normals)?;
        }
        if let Some(c) = &self.values {
            c.read_f32(t.start, t.count, &mut into.values)?;
        }
        if let Some(c) = &self.flags {
            c.read_u8(t.start, t.count, &mut into.flags)?;
        }
        Ok(())
    }
}

/// Output slots of the computed columns for the consecutive input ids
/// from `first`.
pub(super) struct Slots<'a> {
    pub(super) first: u64,
    pub(super) len: usize,
    pub(super) normals: Option<&'a mut [Vec3]>,
    /// `per_point` values a slot.
    pub(super) values: Option<&'a mut [f32]>,
    pub(super) per_point: usize,
    pub(super) flags: Option<&'a mut [u8]>,
}

impl<'a> Slots<'a> {
    /// Input ids of the slots.
    pub(super) fn range(&self) -> std::ops::Range<u64> {
        self.first..self.first + self.len as u64
    }

    /// Fills slot `slot` (an offset from `first`) with a point's normal,
    /// values and flags.
    #[inline]
    pub(super) fn place(&mut self, slot: usize, normal: &[f32], values: &[f32], flags: u8) {
        if let Some(ns) = &mut self.normals {
            ns[slot] = Vec3::new(normal[0], normal[1], normal[2]);
        }
        if let Some(vs) = &mut self.values {
            let per = self.per_point;
            vs[per * slot..per * (slot + 1)].copy_from_slice(values);
        }
        if let Some(fs) = &mut self.flags {
            fs[slot] = flags;
        }
    }

    /// Splits into `parts` consecutive id ranges (the last may be shorter).
    pub(super) fn split(self, parts: usize) -> Vec<Slots<'a>> {
        let per = self.len.div_ceil(parts.max(1)).max(1);
        let per_point = self.per_point;
        let mut normals = self.normals.map(|s| s.chunks_mut(per));
        let mut values = self.values.map(|s| s.chunks_mut(per * per_point.max(1)));
        let mut flags = self.flags.map(|s| s.chunks_mut(per));
        (0..self.len.div_ceil(per))
            .map(|k| Slots {
                first: self.first + (k * per) as u64,
                len: per.min(self.len - k * per),
                normals: normals.as_mut().and_then(|it| it.next()),
                values: values.as_mut().and_then(|it| it.next()),
                per_point,
                flags: flags.as_mut().and_then(|it| it.next()),
            })
            .collect()
    }
}
