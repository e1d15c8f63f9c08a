//! `scanmesh curvature`'s output: every point in input order with its
//! curvature, as a binary little-endian PLY (`x y z` double, the input's
//! own coordinates exactly; `k1 k2 H K residual` float, `flags` uchar; NaN
//! where a flag says the value is not available).

use super::curvature::VALUES;
use super::order::write_in_input_order;
use super::{FeaturesError, CURVATURE, CURVATURE_FLAGS};
use crate::io::{AtomicFile, IoError};
use crate::store::{PointStore, StoreError};
use std::io::{BufWriter, Write};
use std::path::Path;

/// Bytes of one output record.
pub(crate) const RECORD: usize = 24 + VALUE_BYTES;
/// Bytes of a record's computed part (values and flags), placed in input
/// order before the coordinates join it.
const VALUE_BYTES: usize = 4 * VALUES + 1;

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
    let mut file = AtomicFile::create(path)?;
    {
        let mut out = BufWriter::with_capacity(1 << 20, file.file());
        let os = |e| StoreError::from(IoError::os(path, e));
        out.write_all(header(store.len()).as_bytes()).map_err(os)?;
        let (mut val, mut flg, mut xyz) = (Vec::new(), Vec::new(), Vec::new());
        let emit = |first: u64, placed: &[u8]| {
            let n = (placed.len() / VALUE_BYTES) as u64;
            store.read_exact(first, n, &mut xyz)?;
            for (p, values) in xyz.iter().zip(placed.chunks_exact(VALUE_BYTES)) {
                let [x, y, z] = p.to_array().map(f64::to_le_bytes);
                [&x[..], &y, &z, values]
                    .iter()
                    .try_for_each(|b| out.write_all(b))
                    .map_err(os)?;
            }
            Ok(())
        };
        write_in_input_order(store, VALUE_BYTES, window, emit, |t, _, buf| {
            values.read_f32(t.start, t.count, &mut val)?;
            flags.read_u8(t.start, t.count, &mut flg)?;
            buf.reserve(t.count as usize * VALUE_BYTES);
            for k in 0..t.count as usize {
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
