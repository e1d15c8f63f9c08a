//! The run directory's small files (`run.json`, `done.json`, `stages/`):
//! JSON sealed with a CRC-32 of the value's own JSON, written whole or not
//! at all, so a damaged one is refused, not misread.

use super::RunDirError;
use crate::io::atomic::AtomicFile;
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use std::io::Write;
use std::path::Path;

/// A small file's content and the CRC-32 of its canonical JSON.
#[derive(Serialize, Deserialize)]
struct Sealed<T> {
    crc32: u32,
    value: T,
}

/// Writes `value` to `path`, sealed, whole or not at all.
pub(super) fn write_sealed<T: Serialize>(path: &Path, value: &T) -> Result<(), RunDirError> {
    let write = |e: serde_json::Error| RunDirError::Write {
        path: path.to_path_buf(),
        source: e.into(),
    };
    let crc32 = crc32fast::hash(&serde_json::to_vec(value).map_err(write)?);
    let bytes = serde_json::to_vec_pretty(&Sealed { crc32, value }).map_err(write)?;
    write_atomic(path, &bytes)
}

/// The sealed value in `path`; `None` when there is no such file, an error
/// naming the file when it is not whole.
pub(super) fn read_sealed<T: Serialize + DeserializeOwned>(
    path: &Path,
) -> Result<Option<T>, RunDirError> {
    let bytes = match std::fs::read(path) {
        Ok(b) => b,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(source) => {
            return Err(RunDirError::Read {
                path: path.to_path_buf(),
                source,
            })
        }
    };
    let damaged = || RunDirError::Damaged {
        path: path.to_path_buf(),
    };
    let sealed: Sealed<T> = serde_json::from_slice(&bytes).map_err(|_| damaged())?;
    // Floats and maps serialise canonically, so the value's own JSON is
    // the JSON that was sealed.
    let json = serde_json::to_vec(&sealed.value).map_err(|_| damaged())?;
    match crc32fast::hash(&json) == sealed.crc32 {
        true => Ok(Some(sealed.value)),
        false => Err(damaged()),
    }
}

/// Writes `bytes` to `path` whole or not at all.
pub(super) fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), RunDirError> {
    let mut file = AtomicFile::create(path)?;
    file.file()
        .write_all(bytes)
        .map_err(|source| RunDirError::Write {
            path: path.to_path_buf(),
            source,
        })?;
    Ok(file.commit()?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_changed_value_breaks_the_seal() {
        let dir = tempfile::tempdir().expect("tmp");
        let path = dir.path().join("v.json");
        assert_eq!(read_sealed::<Vec<u32>>(&path).expect("none"), None);
        write_sealed(&path, &vec![1_u32, 2, 3]).expect("write");
        assert_eq!(read_sealed(&path).expect("read"), Some(vec![1_u32, 2, 3]));
        let text = std::fs::read_to_string(&path).expect("text");
        std::fs::write(&path, text.replacen('2', "7", 1)).expect("damage");
        let err = read_sealed::<Vec<u32>>(&path).expect_err("damaged");
        assert!(err.to_string().contains("damaged"), "{err}");
    }
}
