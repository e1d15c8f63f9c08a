//! What the export places for each point: the computed columns the output
//! carries ([`Columns`]: normals, flags) and the output slots of a range of
//! consecutive input ids they fill ([`Slots`]). The export's window passes
//! and the reorder's buckets both fill them, so they live below both.

use super::{Column, StoreError, TileEntry};
use glam::Vec3;

/// The attribute columns the output carries.
pub(super) struct Columns {
    pub(super) normals: Option<Column>,
    pub(super) flags: Option<Column>,
}

impl Columns {
    /// Whether the output carries a computed column (else nothing is placed).
    pub(super) fn any(&self) -> bool {
        self.normals.is_some() || self.flags.is_some()
    }

    /// Reads tile `t`'s normals and flags, those the output carries.
    pub(super) fn read(
        &self,
        t: &TileEntry,
        nrm: &mut Vec<f32>,
        flg: &mut Vec<u8>,
    ) -> Result<(), StoreError> {
        if let Some(c) = &self.normals {
            c.read_f32(t.start, t.count, nrm)?;
        }
        if let Some(c) = &self.flags {
            c.read_u8(t.start, t.count, flg)?;
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
    pub(super) flags: Option<&'a mut [u8]>,
}

impl<'a> Slots<'a> {
    /// Input ids of the slots.
    pub(super) fn range(&self) -> std::ops::Range<u64> {
        self.first..self.first + self.len as u64
    }

    /// Fills slot `slot` (an offset from `first`) with a point's normal
    /// and flags.
    #[inline]
    pub(super) fn place(&mut self, slot: usize, normal: &[f32], flags: u8) {
        if let Some(ns) = &mut self.normals {
            ns[slot] = Vec3::new(normal[0], normal[1], normal[2]);
        }
        if let Some(fs) = &mut self.flags {
            fs[slot] = flags;
        }
    }

    /// Splits into `parts` consecutive id ranges (the last may be shorter).
    pub(super) fn split(self, parts: usize) -> Vec<Slots<'a>> {
        let per = self.len.div_ceil(parts.max(1)).max(1);
        let mut normals = self.normals.map(|s| s.chunks_mut(per));
        let mut flags = self.flags.map(|s| s.chunks_mut(per));
        (0..self.len.div_ceil(per))
            .map(|k| Slots {
                first: self.first + (k * per) as u64,
                len: per.min(self.len - k * per),
                normals: normals.as_mut().and_then(|it| it.next()),
                flags: flags.as_mut().and_then(|it| it.next()),
            })
            .collect()
    }
}
