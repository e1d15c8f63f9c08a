//! Files and directories a run must not leave behind if it is interrupted:
//! scratch stores, partial outputs, spill files. Each is registered while
//! it exists (the returned guard unregisters it when dropped), and
//! [`remove_registered`] removes whatever is registered at that moment: what
//! an application's signal handler calls before it exits. The library
//! installs no handler itself; the command line does.
//!
//! Removing a file another thread is still writing is safe on Unix (the
//! open descriptor keeps the inode until it closes; the name is gone).

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;

static REGISTRY: Mutex<Vec<(u64, PathBuf)>> = Mutex::new(Vec::new());
static NEXT: AtomicU64 = AtomicU64::new(0);

/// Keeps a path registered until dropped.
#[derive(Debug)]
pub struct Registered(u64);

/// Registers `path` (a file, or a directory removed with its contents).
pub fn register(path: &Path) -> Registered {
    let id = NEXT.fetch_add(1, Ordering::Relaxed);
    if let Ok(mut r) = REGISTRY.lock() {
        r.push((id, path.to_path_buf()));
    }
    Registered(id)
}

impl Drop for Registered {
    fn drop(&mut self) {
        if let Ok(mut r) = REGISTRY.lock() {
            r.retain(|(id, _)| *id != self.0);
        }
    }
}

/// Removes every registered path (directories with their contents), most
/// recent first; returns how many were removed.
pub fn remove_registered() -> usize {
    let paths: Vec<PathBuf> = match REGISTRY.lock() {
        Ok(mut r) => r.drain(..).rev().map(|(_, p)| p).collect(),
        Err(_) => return 0,
    };
    paths
        .iter()
        .filter(|p| {
            if p.is_dir() {
                std::fs::remove_dir_all(p).is_ok()
            } else {
                std::fs::remove_file(p).is_ok()
            }
        })
        .count()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn registered_paths_are_removed_and_dropped_ones_kept() {
        let dir = tempfile::tempdir().unwrap();
        let (a, b, c) = (
            dir.path().join("a"),
            dir.path().join("b"),
            dir.path().join("c"),
        );
        std::fs::write(&a, b"x").unwrap();
        std::fs::create_dir(&b).unwrap();
        std::fs::write(b.join("inner"), b"y").unwrap();
        std::fs::write(&c, b"z").unwrap();
        let _ga = register(&a);
        let _gb = register(&b);
        drop(register(&c));
        assert!(remove_registered() >= 2);
        assert!(!a.exists() && !b.exists());
        assert!(c.exists(), "an unregistered path was removed");
    }
}
