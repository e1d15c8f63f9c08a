//! Library errors say what is wrong in the library's terms; where a
//! command-line flag is the fix, the command line names it on top.

use scanmesh::io::IoError;
use scanmesh::pipeline::BudgetError;
use scanmesh::store::StoreError;
use scanmesh::units::human_bytes;

/// `err` with the flag that fixes it named first, when one does: `--mem`
/// for a budget no plan fits, `--skip-invalid` for a non-finite input
/// coordinate or a last line without end of line.
pub fn with_flag_hints(err: anyhow::Error) -> anyhow::Error {
    let hint = err.chain().find_map(|cause| {
        let budget =
            cause
                .downcast_ref::<BudgetError>()
                .or(match cause.downcast_ref::<StoreError>() {
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
        let io = cause
            .downcast_ref::<IoError>()
            .or(match cause.downcast_ref::<StoreError>() {
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
