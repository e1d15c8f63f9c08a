//! `scanmesh curvature`'s output: every point in input order with its
//! curvature, as a binary little-endian PLY (`x y z` double, `k1 k2 H K
//! residual` float, `flags` uchar; NaN where a flag says the value is not
//! available).

use super::curvature::VALUES;
use super::order::write_in_input_order;
use super::{FeaturesError, CURVATURE, CURVATURE_FLAGS};
use crate::io::{AtomicFile, IoError};
use crate::store::PointStore;
use std::io::{BufWriter, Write};
use std::path::Path;

/// Bytes of one output record.
pub(crate) const RECORD: usize = 24 + 4 * VALUES + 1;

/// The PLY header for `n` points.
fn header(n: u64) -> String {
    format!(
        "ply\nformat binary_little_endian 1.0\ncomment scanmesh curvature (paper 5): \
         k1 >= k2 principal, H mean, K Gaussian (convex positive), residual = RMS of the \
         quadratic fit; NaN where flags say so (1 sparse, 2 degenerate, 4 ill-conditioned, \
         8 unoriented)\nelement vertex {n}\nproperty double x\nproperty double y\n\
         property double z\nproperty float k1\nproperty float k2\nproperty float H\n\
         property float K\nproperty float residual\nproperty uchar flags\nend_header\n"
    )
}

/// Writes the store's points and curvature columns to `path` in input
/// order, holding about `window` records in memory.
pub fn write_curvature_ply(
    store: &PointStore,
    path: &Path,
    window: u64,
) -> Result<(), FeaturesError> {
    let values = store.column(&CURVATURE)?;
    let flags = store.column(&CURVATURE_FLAGS)?;
    let origin = store.origin();
    let mut file = AtomicFile::create(path)?;
    {
        let mut out = BufWriter::with_capacity(1 << 20, file.file());
        out.write_all(header(store.len()).as_bytes())
            .map_err(|e| IoError::os(path, e))?;
        let (mut xyz, mut val, mut flg) = (Vec::new(), Vec::new(), Vec::new());
        write_in_input_order(store, RECORD, window, &mut out, |t, _, buf| {
            store.read_coords(t.start, t.count, &mut xyz)?;
            values.read_f32(t.start, t.count, &mut val)?;
            flags.read_u8(t.start, t.count, &mut flg)?;
            buf.reserve(t.count as usize * RECORD);
            for k in 0..t.count as usize {
                for a in 0..3 {
                    let abs = origin[a] + f64::from(xyz[3 * k + a]);
                    buf.extend_from_slice(&abs.to_le_bytes());
                }
                for v in &val[VALUES * k..VALUES * (k + 1)] {
                    buf.extend_from_slice(&v.to_le_bytes());
                }
                buf.push(flg[k]);
            }
            Ok(())
        })?;
        out.flush().map_err(|e| IoError::os(path, e))?;
    }
    file.commit()?;
    Ok(())
}
