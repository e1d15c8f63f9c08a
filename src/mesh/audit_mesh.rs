//! Auditing a mesh held in memory ([`audit_mesh`]): validated, then fed to
//! the streaming audit ([`super::audit`]) a batch at a time, as a writer
//! feeds it. It stands apart from the audit because it fails with a
//! [`MeshError`], and `MeshError` names the audit's report and promise.

use super::audit::{Auditor, MeshAudit, Sizes};
use super::{Mesh, MeshError};
use crate::io::IoError;
use std::path::Path;

/// Audits `mesh` (validated first), with its scratch files in
/// `scratch_dir`.
pub fn audit_mesh(mesh: &Mesh, scratch_dir: &Path) -> Result<MeshAudit, MeshError> {
    audit_mesh_sized(mesh, scratch_dir, Sizes::DEFAULT)
}

/// [`audit_mesh`] with the buffers of `sizes`.
pub(crate) fn audit_mesh_sized(
    mesh: &Mesh,
    scratch_dir: &Path,
    sizes: Sizes,
) -> Result<MeshAudit, MeshError> {
    mesh.validate()?;
    let beside = scratch_dir.join("audit");
    let os = |e| MeshError::Io(IoError::os(scratch_dir, e));
    let mut auditor = Auditor::new(&beside, sizes).map_err(os)?;
    const BATCH: usize = 1 << 16;
    for chunk in mesh.vertices.chunks(BATCH) {
        auditor.add_vertices(chunk).map_err(os)?;
    }
    for chunk in mesh.triangles.chunks(BATCH) {
        auditor.add_triangles(chunk).map_err(os)?;
    }
    auditor.finish().map_err(os)
}
