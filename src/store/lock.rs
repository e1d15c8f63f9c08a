//! The store's advisory lock: two processes on one store must not corrupt
//! each other (a column truncated while another process has it mapped
//! would kill that process with SIGBUS). A run that writes columns holds
//! the lock exclusively, readers share it; the second writer gets
//! [`StoreError::Busy`] at once instead of waiting. The lock is `flock` on
//! a file inside the store, released by the kernel when the process ends,
//! however it ends.

use super::StoreError;
use rustix::fs::{flock, FlockOperation};
use std::fs::File;
use std::path::Path;

const LOCK_FILE: &str = ".lock";

#[derive(Debug)]
pub(crate) struct StoreLock {
    _file: File,
}

impl StoreLock {
    pub(crate) fn exclusive(dir: &Path) -> Result<Self, StoreError> {
        Self::take(dir, FlockOperation::NonBlockingLockExclusive)
    }

    pub(crate) fn shared(dir: &Path) -> Result<Self, StoreError> {
        Self::take(dir, FlockOperation::NonBlockingLockShared)
    }

    fn take(dir: &Path, op: FlockOperation) -> Result<Self, StoreError> {
        let path = dir.join(LOCK_FILE);
        let file = File::options()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .open(&path)
            .map_err(|e| StoreError::os(&path, e))?;
        match flock(&file, op) {
            Ok(()) => Ok(StoreLock { _file: file }),
            Err(rustix::io::Errno::WOULDBLOCK) => Err(StoreError::Busy {
                path: dir.to_path_buf(),
            }),
            Err(e) => Err(StoreError::os(&path, e.into())),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_second_writer_is_refused_readers_share() {
        let dir = tempfile::tempdir().unwrap();
        let w = StoreLock::exclusive(dir.path()).unwrap();
        assert!(matches!(
            StoreLock::exclusive(dir.path()),
            Err(StoreError::Busy { .. })
        ));
        assert!(StoreLock::shared(dir.path()).is_err());
        drop(w);
        let r1 = StoreLock::shared(dir.path()).unwrap();
        let _r2 = StoreLock::shared(dir.path()).unwrap();
        assert!(StoreLock::exclusive(dir.path()).is_err());
        drop(r1);
    }
}
