//! Where outputs and scratch files go: checked before any input is read, so
//! a missing or read-only directory, a volume too small for the run, or an
//! output that is the input itself, is reported as what it is (and where),
//! not as a failure to read the input.

use super::{IoError, UnwritableReason};
use std::path::{Path, PathBuf};

/// The directory a file path lands in (`.` for a bare name).
pub fn directory_of(path: &Path) -> PathBuf {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// Checks that `dir` exists, is a directory, and takes a new file; `what`
/// names the role in the error (for example "output" or "scratch").
pub fn check_writable_dir(dir: &Path, what: &'static str) -> Result<(), IoError> {
    let fail = |reason| IoError::Unwritable {
        path: dir.to_path_buf(),
        reason,
    };
    match std::fs::metadata(dir) {
        Err(cause) => return Err(fail(UnwritableReason::Unusable { role: what, cause })),
        Ok(m) if !m.is_dir() => return Err(fail(UnwritableReason::NotADirectory { role: what })),
        Ok(_) => {}
    }
    let probe = dir.join(format!(".scanmesh-probe-{}", std::process::id()));
    match std::fs::File::create(&probe) {
        Ok(_) => {
            let _ = std::fs::remove_file(&probe);
            Ok(())
        }
        Err(cause) => Err(fail(UnwritableReason::NotWritable { role: what, cause })),
    }
}

/// Checks that `output` can be created: its directory is writable and the
/// path itself is not a directory.
pub fn check_output(output: &Path) -> Result<(), IoError> {
    if output.is_dir() {
        return Err(IoError::Unwritable {
            path: output.to_path_buf(),
            reason: UnwritableReason::OutputIsADirectory,
        });
    }
    check_writable_dir(&directory_of(output), "output")
}

/// Refuses an `output` that is the `input` itself (the same file by any
/// path), before anything is read or written.
pub fn check_distinct(input: &Path, output: &Path) -> Result<(), IoError> {
    if let (Ok(a), Ok(b)) = (input.canonicalize(), output.canonicalize()) {
        if a == b {
            return Err(IoError::OverwritesInput {
                path: output.to_path_buf(),
            });
        }
    }
    Ok(())
}

/// Bytes available to this user on the file system holding `dir`.
pub(crate) fn available_bytes(dir: &Path) -> Option<u64> {
    let s = rustix::fs::statvfs(dir).ok()?;
    Some(s.f_bavail.saturating_mul(s.f_frsize))
}

/// Device of the file system holding `dir` (to tell whether two
/// directories share one).
fn device(dir: &Path) -> Option<u64> {
    use std::os::unix::fs::MetadataExt;
    std::fs::metadata(dir).ok().map(|m| m.dev())
}

/// The free space a run leaves to the rest of the machine: a twentieth of
/// what is free, at least 64 MiB and at most 4 GiB (a volume filled to its
/// last byte stops the logs, the shell and the other jobs on it too).
pub fn kept_free(free: u64) -> u64 {
    (free / 20).clamp(64 << 20, 4 << 30).min(free)
}

/// Checks the free space for `scratch` bytes in `scratch_dir` and `output`
/// bytes in `output_dir`, or `both` when they share a file system (at most
/// their sum: a run's scratch shrinks before its output grows), less what
/// is kept free ([`kept_free`]).
pub fn check_space(
    scratch_dir: &Path,
    scratch: u64,
    output_dir: &Path,
    output: u64,
    both: u64,
) -> Result<(), IoError> {
    let same = device(scratch_dir).is_some() && device(scratch_dir) == device(output_dir);
    let needs: Vec<(&Path, u64, &'static str)> = if same {
        vec![(scratch_dir, both, "scratch files and output")]
    } else {
        vec![
            (scratch_dir, scratch, "scratch files"),
            (output_dir, output, "output"),
        ]
    };
    for (dir, bytes, what) in needs {
        if let Some(free) = available_bytes(dir) {
            let kept = kept_free(free);
            if free - kept < bytes {
                return Err(IoError::Unwritable {
                    path: dir.to_path_buf(),
                    reason: UnwritableReason::NoSpace {
                        what,
                        needed: bytes,
                        free,
                        kept,
                    },
                });
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_twentieth_of_the_free_space_is_kept_within_64mib_and_4gib() {
        let (mib, gib) = (1u64 << 20, 1u64 << 30);
        assert_eq!(kept_free(10 * mib), 10 * mib);
        assert_eq!(kept_free(100 * mib), 64 * mib);
        assert_eq!(kept_free(20 * gib), gib);
        assert_eq!(kept_free(1000 * gib), 4 * gib);
    }

    #[test]
    fn missing_read_only_and_directory_outputs_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        assert!(check_output(&dir.path().join("out.ply")).is_ok());
        let missing = dir.path().join("no/such/out.ply");
        let e = check_output(&missing).unwrap_err().to_string();
        assert!(
            e.contains("no/such") && e.contains("output directory"),
            "{e}"
        );
        assert!(!dir.path().join("no").exists(), "a directory was created");
        assert!(check_output(dir.path()).is_err());
        assert!(check_output(Path::new("/proc/out.ply")).is_err());
    }

    #[test]
    fn space_is_checked_against_the_volume() {
        let dir = tempfile::tempdir().unwrap();
        assert!(check_space(dir.path(), 1, dir.path(), 1, 2).is_ok());
        let e = check_space(dir.path(), u64::MAX / 4, dir.path(), 0, u64::MAX / 4).unwrap_err();
        assert!(e.to_string().contains("free"), "{e}");
    }
}
