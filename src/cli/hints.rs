//! Library errors say what is wrong in the library's terms; where a
//! command-line flag is the fix, the command line names it on top.

use scanmesh::demo::DemoError;
use scanmesh::io::IoError;
use scanmesh::pipeline::{BudgetError, WorkspaceError};
use scanmesh::rundir::RunDirError;
use scanmesh::store::{Causes, StoreError};
use scanmesh::units::human_bytes;

/// `err` with the flag that fixes it named first, when one does: `--mem`
/// for a budget no plan fits, `--skip-invalid` for a non-finite input
/// coordinate or a last line without end of line.
pub fn with_flag_hints(err: anyhow::Error) -> anyhow::Error {
    let hint = err.chain().find_map(|cause| {
        // A run's workspace wraps the store's and the budget's errors, and
        // a run directory's and the demo's wrap the workspace's and the
        // store's (transparently, so they are not links of the chain of
        // their own): each says what it comes down to.
        let causes = (cause.downcast_ref::<RunDirError>().map(RunDirError::causes))
            .or_else(|| cause.downcast_ref::<DemoError>().map(DemoError::causes))
            .or_else(|| {
                cause
                    .downcast_ref::<WorkspaceError>()
                    .map(WorkspaceError::causes)
            })
            .or_else(|| cause.downcast_ref::<StoreError>().map(StoreError::causes))
            .unwrap_or(Causes {
                budget: cause.downcast_ref(),
                input: cause.downcast_ref(),
            });
        if let Some(BudgetError::TooSmall { budget, needed, .. }) = causes.budget {
            return Some(format!(
                "--mem {} is too small: give at least {}",
                human_bytes(*budget),
                human_bytes(*needed)
            ));
        }
        match causes.input {
            Some(IoError::NonFinite { .. }) => {
                Some("a coordinate is not finite (--skip-invalid drops such points)".to_string())
            }
            Some(IoError::CutShort { .. }) => {
                Some("the last line may be cut short (--skip-invalid drops it)".to_string())
            }
            _ => None,
        }
    });
    match hint {
        Some(hint) => err.context(hint),
        None => err,
    }
}
