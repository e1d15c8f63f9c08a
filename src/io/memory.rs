//! An in-memory [`PointReader`]: for tests, benches and the embedded demo.

use super::{Format, IoError, PointChunk, PointReader, SourceInfo};
use glam::{DVec3, Vec3};
use std::path::PathBuf;

/// Serves points from vectors, as if they were a file.
pub struct MemoryReader {
    info: SourceInfo,
    xyz: Vec<DVec3>,
    normals: Option<Vec<Vec3>>,
    pos: usize,
    stations: Vec<super::ScanStation>,
}

impl MemoryReader {
    /// A reader over points already in memory, reported under the name `name`; `normals`, when given, has one normal per point.
    pub fn new(name: &str, xyz: Vec<DVec3>, normals: Option<Vec<Vec3>>) -> Self {
        let info = SourceInfo {
            path: PathBuf::from(name),
            format: Format::PlyBinaryLe,
            gzip: false,
            declared_count: Some(xyz.len() as u64),
            has_normals: normals.is_some(),
            attributes: crate::io::AttributeSet::EMPTY,
            header_bounds: None,
            las_transform: None,
        };
        MemoryReader {
            info,
            xyz,
            normals,
            pos: 0,
            stations: Vec::new(),
        }
    }

    /// The same reader, saying where the scanner stood for each run of
    /// its points (as an E57 file's scans do).
    pub fn with_stations(mut self, stations: Vec<super::ScanStation>) -> Self {
        self.stations = stations;
        self
    }
}

impl PointReader for MemoryReader {
    fn info(&self) -> &SourceInfo {
        &self.info
    }

    fn stations(&self) -> Vec<super::ScanStation> {
        self.stations.clone()
    }

    fn read_chunk(&mut self, chunk: &mut PointChunk, max: usize) -> Result<usize, IoError> {
        chunk.clear();
        chunk.indices = None;
        chunk.attrs.reset(self.info.attributes);
        let end = (self.pos + max).min(self.xyz.len());
        chunk.first_index = self.pos as u64;
        for (i, p) in self.xyz[self.pos..end].iter().enumerate() {
            if !p.is_finite() {
                return Err(IoError::NonFinite {
                    path: self.info.path.clone(),
                    record: (self.pos + i) as u64,
                    value: if p.x.is_finite() {
                        if p.y.is_finite() {
                            p.z
                        } else {
                            p.y
                        }
                    } else {
                        p.x
                    },
                });
            }
        }
        chunk.xyz.extend_from_slice(&self.xyz[self.pos..end]);
        chunk.normals = self.normals.as_ref().map(|n| n[self.pos..end].to_vec());
        let n = end - self.pos;
        self.pos = end;
        Ok(n)
    }

    fn skipped(&self) -> u64 {
        0
    }
}
