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
         8 unoriented, 128 not selected)\nelement vertex {n}\nproperty double x\nproperty double y\n\
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
    write_curvature_ply_keeping(store, path, window, None)
}

/// [`write_curvature_ply`]; with `keep`, the input file `keep.0`'s points
/// that its read `keep.1` did not select (the store holds the selected
/// ones) get their rows too, in input order: NaN values, flag
/// [`crate::io::keep::UNSELECTED`].
pub fn write_curvature_ply_keeping(
    store: &PointStore,
    path: &Path,
    window: u64,
    keep: Option<(&Path, &crate::io::ReadOptions)>,
) -> Result<(), FeaturesError> {
    let values = store.column(&CURVATURE)?;
    let flags = store.column(&CURVATURE_FLAGS)?;
    let mut rows = keep
        .map(|(input, read)| crate::io::keep::UnselectedRows::open(input, read))
        .transpose()
        .map_err(StoreError::from)?;
    let unselected = match rows {
        Some(_) => store.manifest().left_out.unselected,
        None => 0,
    };
    let mut none = [0u8; VALUE_BYTES];
    for v in none.chunks_exact_mut(4).take(VALUES) {
        v.copy_from_slice(&f32::NAN.to_le_bytes());
    }
    none[VALUE_BYTES - 1] = crate::io::keep::UNSELECTED;
    let mut file = AtomicFile::create(path)?;
    {
        let mut out = BufWriter::with_capacity(1 << 20, file.file());
        let os = |e| StoreError::from(IoError::os(path, e));
        out.write_all(header(store.len() + unselected).as_bytes())
            .map_err(os)?;
        let (mut val, mut flg, mut xyz) = (Vec::new(), Vec::new(), Vec::new());
        // The unselected points before the next selected one; `false` when
        // the input has no selected point left.
        let mut unselected_first = |out: &mut BufWriter<_>| -> Result<bool, StoreError> {
            match &mut rows {
                Some(r) => r.up_to_selected(|p, _, _| write_record(out, path, p, &none)),
                None => Ok(true),
            }
        };
        let emit = |first: u64, placed: &[u8]| {
            let n = (placed.len() / VALUE_BYTES) as u64;
            store.read_exact(first, n, &mut xyz)?;
            for (p, values) in xyz.iter().zip(placed.chunks_exact(VALUE_BYTES)) {
                if !unselected_first(&mut out)? {
                    return Err(not_the_input(path));
                }
                write_record(&mut out, path, *p, values)?;
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
        // The unselected points after the last selected one.
        if let Some(r) = &mut rows {
            if r.up_to_selected(|p, _, _| write_record(&mut out, path, p, &none))? {
                return Err(not_the_input(path).into());
            }
        }
        out.flush().map_err(|e| IoError::os(path, e))?;
    }
    file.commit()?;
    Ok(())
}

/// One record: the point's coordinates, then its values and flags.
fn write_record(
    out: &mut impl Write,
    path: &Path,
    p: glam::DVec3,
    values: &[u8],
) -> Result<(), StoreError> {
    let [x, y, z] = p.to_array().map(f64::to_le_bytes);
    [&x[..], &y, &z, values]
        .iter()
        .try_for_each(|b| out.write_all(b))
        .map_err(|e| StoreError::from(IoError::os(path, e)))
}

/// The input read again does not hold the store's selected points.
fn not_the_input(path: &Path) -> StoreError {
    StoreError::from(IoError::Unsupported {
        path: path.to_path_buf(),
        reason: "the input's selected points are not the store's: the input changed during the run"
            .into(),
    })
}
