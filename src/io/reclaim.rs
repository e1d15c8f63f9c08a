//! Scratch that killed runs left behind: a process ended by SIGKILL (the
//! OOM killer, a scheduler's time limit) runs no cleanup, so its scratch
//! store (`.NAME.store-PID`, a directory) and its unfinished output
//! (`.NAME.partial-PID`) stay beside the output for ever, 32 MB per
//! million points. The next run in that place reclaims them.
//!
//! Only scratch whose process is gone is touched, and that is decided by
//! the lock the owner holds for as long as it lives (an `flock`, which the
//! kernel drops with the process however it ends, also on a network file
//! system shared by the nodes of a cluster), not by the PID alone: a PID is
//! only meaningful on its own host. A live PID on this host keeps its
//! scratch too, whatever its lock says (a lock not yet taken in the moment
//! after the scratch was made, or a file system without locks).

use rustix::fs::{flock, FlockOperation};
use std::fs::File;
use std::path::{Path, PathBuf};
use std::time::{Duration, SystemTime};

/// The lock file inside a scratch store (`store::lock` takes it).
const STORE_LOCK: &str = ".lock";
/// A scratch store without a lock file (a build killed before it took
/// one, or one of an older scanmesh) is reclaimed only after this long.
const UNLOCKED_AGE: Duration = Duration::from_secs(3600);

/// Which kind of scratch a name is, and its owner's PID.
fn scratch_kind(name: &str) -> Option<(Kind, u32)> {
    let rest = name.strip_prefix('.')?;
    for (marker, kind) in [(".store-", Kind::Store), (".partial-", Kind::Partial)] {
        if let Some((_, pid)) = rest.rsplit_once(marker) {
            if !pid.is_empty() && pid.bytes().all(|b| b.is_ascii_digit()) {
                return Some((kind, pid.parse().ok()?));
            }
        }
    }
    None
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    /// A scratch store directory, locked through its `.lock` file.
    Store,
    /// A partial output file, locked itself.
    Partial,
}

/// Whether process `pid` runs on this host.
fn alive_here(pid: u32) -> bool {
    pid == std::process::id() || Path::new("/proc").join(pid.to_string()).exists()
}

/// Whether nobody holds the lock on `file` (taken and released at once).
fn unlocked(file: &Path) -> bool {
    let Ok(f) = File::open(file) else {
        return false;
    };
    flock(&f, FlockOperation::NonBlockingLockExclusive).is_ok()
}

/// Whether the scratch entry at `path` belongs to no live run.
fn abandoned(path: &Path, kind: Kind, pid: u32) -> bool {
    if alive_here(pid) {
        return false;
    }
    match kind {
        Kind::Partial => unlocked(path),
        Kind::Store => {
            let lock = path.join(STORE_LOCK);
            match lock.exists() {
                true => unlocked(&lock),
                false => older_than(path, UNLOCKED_AGE),
            }
        }
    }
}

fn older_than(path: &Path, age: Duration) -> bool {
    std::fs::metadata(path)
        .and_then(|m| m.modified())
        .ok()
        .and_then(|t| SystemTime::now().duration_since(t).ok())
        .is_some_and(|d| d > age)
}

/// Removes the scratch entries in `dir` that killed runs left; returns
/// what it removed. Entries it cannot read or remove are left as they are
/// (this is housekeeping: it never fails a run).
pub fn reclaim_scratch(dir: &Path) -> Vec<PathBuf> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    let mut removed = Vec::new();
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some((kind, pid)) = scratch_kind(&name.to_string_lossy()) else {
            continue;
        };
        let path = entry.path();
        let is_dir = entry.file_type().is_ok_and(|t| t.is_dir());
        if is_dir != (kind == Kind::Store) || !abandoned(&path, kind, pid) {
            continue;
        }
        let gone = match is_dir {
            true => std::fs::remove_dir_all(&path),
            false => std::fs::remove_file(&path),
        };
        if gone.is_ok() {
            removed.push(path);
        }
    }
    removed.sort();
    removed
}

/// Takes `file`'s lock for the life of the descriptor: what tells
/// [`reclaim_scratch`] that its owner lives. Best effort: on a file system
/// without locks the owner's PID still protects it on its own host.
pub(crate) fn hold(file: &File) {
    let _ = flock(file, FlockOperation::NonBlockingLockExclusive);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A PID no process has: beyond the kernel's largest.
    const DEAD: u32 = 4_194_304 + 17;

    #[test]
    fn names_are_read_strictly() {
        assert_eq!(scratch_kind(".out.ply.store-123"), Some((Kind::Store, 123)));
        assert_eq!(scratch_kind(".a.las.partial-9"), Some((Kind::Partial, 9)));
        for other in [
            "out.ply.store-123",
            ".x.store-",
            ".x.store-12a",
            ".lock",
            "run",
        ] {
            assert_eq!(scratch_kind(other), None, "{other}");
        }
    }

    #[test]
    fn only_scratch_of_dead_unlocked_owners_is_removed() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        // Dead owner, unlocked: removed (a store and a partial output).
        let dead_store = d.join(format!(".a.ply.store-{DEAD}"));
        std::fs::create_dir(&dead_store).unwrap();
        std::fs::write(dead_store.join(STORE_LOCK), b"").unwrap();
        std::fs::write(dead_store.join("xyz.f32"), b"data").unwrap();
        let dead_partial = d.join(format!(".a.ply.partial-{DEAD}"));
        std::fs::write(&dead_partial, b"half").unwrap();
        // Dead PID but the lock is held (a live run on another host).
        let held_store = d.join(format!(".b.ply.store-{}", DEAD + 1));
        std::fs::create_dir(&held_store).unwrap();
        let lock = File::create(held_store.join(STORE_LOCK)).unwrap();
        hold(&lock);
        let held_partial = d.join(format!(".b.ply.partial-{}", DEAD + 1));
        let partial = File::create(&held_partial).unwrap();
        hold(&partial);
        // This process's own scratch, unlocked, and a fresh store without
        // a lock file: kept.
        let own = d.join(format!(".c.ply.partial-{}", std::process::id()));
        std::fs::write(&own, b"mine").unwrap();
        let fresh = d.join(format!(".d.ply.store-{}", DEAD + 2));
        std::fs::create_dir(&fresh).unwrap();
        // A user's files that look alike but are not scratch.
        std::fs::write(d.join("a.ply.store-1"), b"user").unwrap();
        std::fs::create_dir(d.join(format!(".e.ply.partial-{DEAD}"))).unwrap();
        let removed = reclaim_scratch(d);
        assert_eq!(removed, vec![dead_partial.clone(), dead_store.clone()]);
        assert!(!dead_store.exists() && !dead_partial.exists());
        for kept in [&held_store, &held_partial, &own, &fresh] {
            assert!(kept.exists(), "{} was removed", kept.display());
        }
        assert!(d.join("a.ply.store-1").exists());
        assert!(d.join(format!(".e.ply.partial-{DEAD}")).exists());
        drop((lock, partial));
        assert_eq!(reclaim_scratch(d), vec![held_partial, held_store]);
    }
}
