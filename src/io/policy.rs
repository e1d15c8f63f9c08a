//! Admission of decoded records into a [`PointChunk`]: the one place that
//! enforces finite coordinates and keeps input indices right when
//! [`InvalidPolicy::Skip`] drops records.

use super::{AttributeValues, InvalidPolicy, IoError, PointChunk, SourceInfo};
use glam::{DVec3, Vec3};
use std::path::PathBuf;

pub(crate) struct Admitter {
    path: PathBuf,
    policy: InvalidPolicy,
    skipped: u64,
    no_return: u64,
}

impl Admitter {
    pub fn new(path: PathBuf, policy: InvalidPolicy) -> Self {
        Admitter {
            path,
            policy,
            skipped: 0,
            no_return: 0,
        }
    }

    pub fn skipped(&self) -> u64 {
        self.skipped
    }

    /// Records passed by [`Admitter::no_return`].
    pub fn no_return_count(&self) -> u64 {
        self.no_return
    }

    /// Clears `chunk` for records starting at input index `first`, keeping
    /// its allocations, ready for the normals and attributes of `info`.
    pub fn begin(&self, chunk: &mut PointChunk, first: u64, info: &SourceInfo) {
        chunk.xyz.clear();
        chunk.first_index = first;
        chunk.indices = None;
        chunk.attrs.reset(info.attributes);
        chunk.number_of_returns.clear();
        if info.has_normals {
            match &mut chunk.normals {
                Some(n) => n.clear(),
                None => chunk.normals = Some(Vec::new()),
            }
        } else {
            chunk.normals = None;
        }
    }

    /// Appends input record `record` unless its coordinates are not finite.
    #[inline]
    pub fn push(
        &mut self,
        chunk: &mut PointChunk,
        record: u64,
        p: DVec3,
        normal: Vec3,
    ) -> Result<(), IoError> {
        self.push_with(chunk, record, p, normal, &AttributeValues::default())
    }

    /// [`Admitter::push`] with the record's attribute values (those of the
    /// chunk's set are kept).
    #[inline]
    pub fn push_with(
        &mut self,
        chunk: &mut PointChunk,
        record: u64,
        p: DVec3,
        normal: Vec3,
        attrs: &AttributeValues,
    ) -> Result<(), IoError> {
        if !p.is_finite() {
            return self.reject(chunk, record, p);
        }
        chunk.xyz.push(p);
        chunk.attrs.push(attrs);
        if let Some(n) = &mut chunk.normals {
            n.push(normal);
        }
        if let Some(ix) = &mut chunk.indices {
            ix.push(record);
        }
        Ok(())
    }

    #[cold]
    fn reject(&mut self, chunk: &mut PointChunk, record: u64, p: DVec3) -> Result<(), IoError> {
        match self.policy {
            InvalidPolicy::Reject => {
                let value = [p.x, p.y, p.z]
                    .into_iter()
                    .find(|v| !v.is_finite())
                    .unwrap_or(f64::NAN);
                Err(IoError::NonFinite {
                    path: self.path.clone(),
                    record,
                    value,
                })
            }
            InvalidPolicy::Skip => {
                self.skipped += 1;
                explicit_indices(chunk);
                Ok(())
            }
        }
    }

    /// Input record `record`, on line `line`, is the input's last line and
    /// has no end of line: it may be cut inside its last number, so it is
    /// never taken as a point. An error under [`InvalidPolicy::Reject`];
    /// dropped and counted with the other invalid records under
    /// [`InvalidPolicy::Skip`].
    #[cold]
    pub fn cut(&mut self, chunk: &mut PointChunk, record: u64, line: u64) -> Result<(), IoError> {
        match self.policy {
            InvalidPolicy::Reject => Err(IoError::CutShort {
                path: self.path.clone(),
                record,
                line,
            }),
            InvalidPolicy::Skip => {
                self.skipped += 1;
                explicit_indices(chunk);
                Ok(())
            }
        }
    }

    /// Drops a record the file itself marks as no point (E57's invalid
    /// states), under every policy; the reader counts these itself.
    pub fn pass(&self, chunk: &mut PointChunk) {
        explicit_indices(chunk);
    }

    /// Drops a pixel of an organised cloud where the sensor saw nothing
    /// (NaN coordinates), under every policy, and counts it apart from the
    /// invalid records ([`crate::io::LeftOut::no_return`]).
    pub fn no_return(&mut self, chunk: &mut PointChunk) {
        self.no_return += 1;
        explicit_indices(chunk);
    }

    /// The next record is `record`, which need not follow the last one (a
    /// reader that leaves out whole parts of its file, as E57 scans).
    pub fn jump(&self, chunk: &mut PointChunk, record: u64) {
        if chunk.indices.is_some() {
            return;
        }
        if chunk.xyz.is_empty() {
            chunk.first_index = record;
        } else if chunk.first_index + chunk.xyz.len() as u64 != record {
            explicit_indices(chunk);
        }
    }

    /// Makes `first_index` the index of `xyz[0]` again after skips.
    pub fn end(&self, chunk: &mut PointChunk) -> usize {
        if let Some(&first) = chunk.indices.as_ref().and_then(|ix| ix.first()) {
            chunk.first_index = first;
        }
        chunk.xyz.len()
    }
}

/// Makes a chunk's indices explicit (records are about to be left out).
fn explicit_indices(chunk: &mut PointChunk) {
    if chunk.indices.is_none() {
        // No gap so far in this chunk: positions were implicit.
        let first = chunk.first_index;
        chunk.indices = Some((first..first + chunk.xyz.len() as u64).collect());
    }
}
