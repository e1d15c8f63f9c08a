//! `scanmesh curvature`'s output: every point in input order with its
//! curvature (`k1 k2 H K residual` float, NaN where a flag says the value
//! is not available, and the flags byte), written by the store's point
//! export ([`crate::store::export_columns`]) in whichever format the
//! output table gives ([`crate::io::output_spec`]): PLY properties, PCD
//! fields, LAS extra bytes (a LAS input's own records kept as they came).

use super::{FeaturesError, CURVATURE, CURVATURE_FLAGS};
use crate::io::{output_spec, Carried, IoError, ValueField, WriterSpec};
use crate::store::{export_values, PointStore, Rows};
use std::path::Path;

/// The curvature's fields, in the column's order.
pub const CURVATURE_FIELDS: [ValueField; super::curvature::VALUES] = [
    ValueField {
        name: "k1",
        description: "larger principal curvature",
    },
    ValueField {
        name: "k2",
        description: "smaller principal curvature",
    },
    ValueField {
        name: "H",
        description: "mean curvature",
    },
    ValueField {
        name: "K",
        description: "Gaussian curvature",
    },
    ValueField {
        name: "residual",
        description: "RMS of the quadratic fit",
    },
];

/// What the file holds, where its format has a comment.
const COMMENT: &str = "scanmesh curvature (paper 5): k1 >= k2 principal, H mean, K Gaussian \
     (convex positive), residual = RMS of the quadratic fit; NaN where flags say so (1 sparse, \
     2 degenerate, 4 ill-conditioned, 8 unoriented, 128 not selected)";

/// The writer spec of a curvature output named `path`: an error names
/// the file when its format cannot hold the curvature.
pub fn curvature_output(path: &Path) -> Result<WriterSpec, IoError> {
    let carried = Carried::values_and_flags(&CURVATURE_FIELDS, COMMENT);
    output_spec(path, &carried, false)
}

/// Writes the store's points and curvature columns to `rows` as `spec`
/// says ([`curvature_output`]), in input order; the points `rows.keep`
/// asks for get their rows too: NaN values, flag
/// [`crate::io::keep::UNSELECTED`]. Returns the rows written.
pub fn write_curvature(
    store: &PointStore,
    spec: &WriterSpec,
    rows: &Rows,
) -> Result<u64, FeaturesError> {
    Ok(export_values(
        store,
        spec,
        [CURVATURE, CURVATURE_FLAGS],
        rows,
    )?)
}
