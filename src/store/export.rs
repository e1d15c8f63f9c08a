//! Writing a store's points (and normals, flags) in input order to any point
//! format. Tiles are in spatial order, the output is in input order: the
//! export fills windows of consecutive input indices, each by one pass over
//! the tiles, so memory is one window plus one tile whatever the store size.

use super::{PointStore, StoreError, FLAGS_FILE, NORMAL_FILE};
use crate::io::{create_writer, PointChunk, WriterSpec};
use crate::pipeline::Progress;
use glam::{DVec3, Vec3};
use std::path::Path;

/// Writes `store` to `path` in input order; returns the points written.
pub fn export_points(
    store: &PointStore,
    path: &Path,
    spec: &WriterSpec,
    window_points: u64,
    progress: &dyn Progress,
) -> Result<u64, StoreError> {
    let normals = if spec.with_normals {
        Some(store.attribute(NORMAL_FILE, 12)?)
    } else {
        None
    };
    let flags = if spec.with_flags {
        Some(store.attribute(FLAGS_FILE, 1)?)
    } else {
        None
    };
    let mut spec = spec.clone();
    if spec.bounds.is_none() {
        spec.bounds = Some(crate::geom::Aabb::new(
            DVec3::from_array(store.manifest.bounds_min),
            DVec3::from_array(store.manifest.bounds_max),
        ));
    }
    let mut writer = create_writer(path, &spec)?;
    let n = store.len();
    let window = window_points.clamp(1, n.max(1));
    let origin = store.origin();
    let (mut pts, mut ids, mut nrm, mut flg) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    progress.begin("write", n);
    let mut w0 = 0;
    while w0 < n {
        let w1 = (w0 + window).min(n);
        let len = (w1 - w0) as usize;
        let mut chunk = PointChunk {
            first_index: w0,
            xyz: vec![DVec3::ZERO; len],
            normals: normals.as_ref().map(|_| vec![Vec3::ZERO; len]),
            indices: None,
        };
        let mut chunk_flags = vec![0u8; if flags.is_some() { len } else { 0 }];
        for t in store.tiles() {
            store.read_indices(t.start, t.count, &mut ids)?;
            if !ids.iter().any(|&i| (w0..w1).contains(&i)) {
                continue;
            }
            store.read_points(t.start, t.count, &mut pts)?;
            if let Some(c) = &normals {
                c.read_f32(t.start, t.count, &mut nrm)?;
            }
            if let Some(c) = &flags {
                c.read_u8(t.start, t.count, &mut flg)?;
            }
            for (k, &id) in ids.iter().enumerate() {
                if !(w0..w1).contains(&id) {
                    continue;
                }
                let slot = (id - w0) as usize;
                chunk.xyz[slot] = origin + pts[k];
                if let Some(ns) = &mut chunk.normals {
                    ns[slot] = Vec3::new(nrm[3 * k], nrm[3 * k + 1], nrm[3 * k + 2]);
                }
                if flags.is_some() {
                    chunk_flags[slot] = flg[k];
                }
            }
        }
        writer.write_chunk(&chunk, flags.as_ref().map(|_| chunk_flags.as_slice()))?;
        progress.advance(len as u64);
        w0 = w1;
    }
    progress.end();
    Ok(writer.finish()?)
}
