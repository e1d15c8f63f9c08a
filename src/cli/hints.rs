//! Library errors say what is wrong in the library's terms; where a
//! command-line flag is the fix, the command line names it on top.

use scanmesh::demo::DemoError;
use scanmesh::io::IoError;
use scanmesh::pipeline::{BudgetError, WorkspaceError};
use scanmesh::rundir::RunDirError;
use scanmesh::store::StoreError;
use scanmesh::units::human_bytes;

/// `err` with the flag that fixes it named first, when one does: `--mem`
/// for a budget no plan fits, `--skip-invalid` for a non-finite input
/// coordinate or a last line without end of line.
pub fn with_flag_hints(err: anyhow::Error) -> anyhow::Error {
    let hint = err.chain().find_map(|cause| {
        // A run's workspace wraps the store's and the budget's errors, and
        // a run directory's and the demo's wrap the workspace's and the
        // store's (transparently, so they are not links of the chain of
        // their own).
        let run = cause.downcast_ref::<RunDirError>();
        let demo = cause.downcast_ref::<DemoError>();
        let ws = match (run, demo) {
            (Some(RunDirError::Workspace(w)), _) | (_, Some(DemoError::Workspace(w))) => Some(w),
            _ => cause.downcast_ref::<WorkspaceError>(),
        };
        let store = match (ws, run, demo) {
            (Some(WorkspaceError::Store(e) | WorkspaceError::Reading { source: e, .. }), _, _) => {
                Some(e)
            }
            (_, Some(RunDirError::Store(e)), _) | (_, _, Some(DemoError::Store(e))) => Some(e),
            _ => cause.downcast_ref::<StoreError>(),
        };
        let budget = match ws {
            Some(WorkspaceError::Budget(b)) => Some(b),
            _ => cause.downcast_ref::<BudgetError>(),
        }
        .or(match store {
            Some(StoreError::Budget(b)) => Some(b),
            _ => None,
        });
        if let Some(BudgetError::TooSmall { budget, needed, .. }) = budget {
            return Some(format!(
                "--mem {} is too small: give at least {}",
                human_bytes(*budget),
                human_bytes(*needed)
            ));
        }
        let io = match ws {
            Some(WorkspaceError::Io(e)) => Some(e),
            _ => cause.downcast_ref::<IoError>(),
        }
        .or(match store {
            Some(StoreError::Input(e)) => Some(e),
            _ => None,
        });
        match io {
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
