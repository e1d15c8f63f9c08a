//! Finished tiles of a resumable run (`--run-dir`): each tile stage's
//! results are kept under the run directory, one file a tile, so a run
//! that dies (a kill, a reboot, a full disk) redoes only the tiles that
//! were in flight, and tile jobs on a cluster can share the work. Also the
//! [`Job`] this process was started for (all of it, up to a stage, or some
//! tiles of one stage, [`TileSet`], as its text reads).
//!
//! A tile file appears whole or not at all: it is written under a
//! temporary name, forced to disk and renamed. It starts with a magic, the
//! payload length and a CRC-32 of the payload, so a file cut or damaged on
//! disk is found, removed and its tile recomputed (a tile is a pure
//! function of the store, itself checked, so nothing wrong reaches the
//! output), and the run is told which ([`Checkpoints::damaged`]).

use super::StoreError;
use crate::io::atomic::AtomicFile;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, OnceLock};

const MAGIC: &[u8; 8] = b"SMTILE2\0";
const HEADER: usize = 24;

/// Which part of the run a process does.
#[derive(Clone, Debug, PartialEq, Eq, Default)]
pub enum Job {
    /// Everything not done yet (a plain run, or a resume).
    #[default]
    Whole,
    /// Everything before the tile stage `stage`, then stop.
    Until(String),
    /// Only `tiles` of the tile stage `stage`, then stop; earlier tile
    /// stages must be complete.
    Tiles {
        /// The tile stage.
        stage: String,
        /// The tiles of that stage to run.
        tiles: TileSet,
    },
}

impl Job {
    /// The job of `tiles` of the tile stage `stage` when both are given,
    /// else everything before the tile stage `until` when given, else the
    /// whole run (`run-job`'s `--stage`, `--tiles` or `--share`, `--until`).
    pub fn of(stage: Option<&str>, tiles: Option<TileSet>, until: Option<&str>) -> Self {
        match (stage, tiles, until) {
            (Some(stage), Some(tiles), _) => Job::Tiles {
                stage: stage.to_string(),
                tiles,
            },
            (_, _, Some(stage)) => Job::Until(stage.to_string()),
            _ => Job::Whole,
        }
    }
}

/// The number `part` of a tile set's `text`.
fn number(text: &str, part: &str) -> Result<usize, TileSetError> {
    part.trim().parse().map_err(|why| TileSetError::Number {
        text: text.into(),
        why,
    })
}

/// Some tiles of a stage.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TileSet {
    /// Tiles `first..=last`.
    Range {
        /// First tile of the range.
        first: usize,
        /// Last tile of the range (inclusive).
        last: usize,
    },
    /// The `index`-th of `count` contiguous, nearly equal shares (a
    /// scheduler's array task does not know the tile count when submitted).
    Share {
        /// Which share, 0-based.
        index: usize,
        /// How many shares the stage is cut into.
        count: usize,
    },
}

/// Why a tile set's text (`run-job --tiles FIRST-LAST`, `--share
/// INDEX/COUNT`, as `--emit`'s scripts write them) names none; the text
/// comes first.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum TileSetError {
    /// A number that is not one.
    #[error("{text}: {why}")]
    Number {
        /// The text given.
        text: String,
        /// Why its number is none.
        why: std::num::ParseIntError,
    },
    /// A range whose last tile comes before its first.
    #[error("{text}: the last tile comes before the first")]
    Backwards {
        /// The text given.
        text: String,
    },
    /// A share without its `/`.
    #[error("{text}: expected INDEX/COUNT")]
    NotAShare {
        /// The text given.
        text: String,
    },
    /// A share past the count.
    #[error("{text}: INDEX must be below COUNT")]
    PastCount {
        /// The text given.
        text: String,
    },
}

impl TileSet {
    /// `FIRST-LAST` (or one tile).
    pub fn parse_range(text: &str) -> Result<Self, TileSetError> {
        let (a, b) = text.split_once('-').unwrap_or((text, text));
        let first = number(text, a)?;
        let last = number(text, b)?;
        if last < first {
            return Err(TileSetError::Backwards { text: text.into() });
        }
        Ok(TileSet::Range { first, last })
    }

    /// `INDEX/COUNT`.
    pub fn parse_share(text: &str) -> Result<Self, TileSetError> {
        let Some((a, b)) = text.split_once('/') else {
            return Err(TileSetError::NotAShare { text: text.into() });
        };
        let (index, count) = (number(text, a)?, number(text, b)?);
        if count == 0 || index >= count {
            return Err(TileSetError::PastCount { text: text.into() });
        }
        Ok(TileSet::Share { index, count })
    }

    /// The tiles of `0..n` in this set.
    pub(crate) fn tiles(&self, n: usize) -> std::ops::Range<usize> {
        match *self {
            TileSet::Range { first, last } => first.min(n)..last.saturating_add(1).min(n),
            TileSet::Share { index, count } => {
                let count = count.max(1);
                (n * index / count).min(n)..(n * (index + 1) / count).min(n)
            }
        }
    }
}

impl std::fmt::Display for TileSet {
    /// As `run-job` takes it: `--tiles 3-5` or `--share 0/16`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            TileSet::Range { first, last } => write!(f, "--tiles {first}-{last}"),
            TileSet::Share { index, count } => write!(f, "--share {index}/{count}"),
        }
    }
}

/// The tile results of a run directory, and this process's job in it.
#[derive(Clone, Debug)]
pub struct Checkpoints {
    dir: PathBuf,
    /// What this process is to do in the run directory.
    pub job: Job,
    /// The stage where the job stopped as asked, shared by the clones (the
    /// application learns it there rather than from an error chain).
    stopped: Arc<OnceLock<String>>,
    /// Tile files found damaged (and removed, to be recomputed).
    damaged: Arc<Mutex<Vec<PathBuf>>>,
}

impl Checkpoints {
    /// Tile results under `dir` (created when needed).
    pub fn new(dir: impl Into<PathBuf>, job: Job) -> Self {
        Checkpoints {
            dir: dir.into(),
            job,
            stopped: Arc::default(),
            damaged: Arc::default(),
        }
    }

    /// Records that the job is done at `stage`.
    pub(crate) fn stop_at(&self, stage: &str) {
        let _ = self.stopped.set(stage.to_string());
    }

    /// The stage where the job stopped as asked, if it did.
    pub fn stopped_at(&self) -> Option<&str> {
        self.stopped.get().map(String::as_str)
    }

    /// A stage name as a directory name ("marching cubes" -> "marching-cubes").
    pub fn slug(stage: &str) -> String {
        stage
            .chars()
            .map(|c| if c.is_ascii_alphanumeric() { c } else { '-' })
            .collect()
    }

    fn stage_dir(&self, stage: &str) -> PathBuf {
        self.dir.join(Self::slug(stage))
    }

    fn tile_path(&self, stage: &str, tile: usize) -> PathBuf {
        self.stage_dir(stage).join(format!("{tile:07}.tile"))
    }

    /// The saved payload of `tile`, if it is there and whole; a damaged
    /// file is removed (the tile is then recomputed).
    pub fn load(&self, stage: &str, tile: usize) -> Result<Option<Vec<u8>>, StoreError> {
        let path = self.tile_path(stage, tile);
        let bytes = match std::fs::read(&path) {
            Ok(b) => b,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
            Err(e) => return Err(StoreError::os(&path, e)),
        };
        match payload(&bytes) {
            Some(p) => Ok(Some(p.to_vec())),
            None => {
                std::fs::remove_file(&path).map_err(|e| StoreError::os(&path, e))?;
                if let Ok(mut d) = self.damaged.lock() {
                    d.push(path);
                }
                Ok(None)
            }
        }
    }

    /// Removes `tile`'s saved result of `stage`, whose content does not fit
    /// the tile (counted with the damaged ones).
    pub(crate) fn reject(&self, stage: &str, tile: usize) -> Result<(), StoreError> {
        let path = self.tile_path(stage, tile);
        std::fs::remove_file(&path).map_err(|e| StoreError::os(&path, e))?;
        if let Ok(mut d) = self.damaged.lock() {
            d.push(path);
        }
        Ok(())
    }

    /// The tile files this process found damaged and removed (their tiles
    /// were recomputed).
    pub fn damaged(&self) -> Vec<PathBuf> {
        self.damaged.lock().map(|d| d.clone()).unwrap_or_default()
    }

    /// Whether `tile` has a saved result (not checked: [`Self::load`] does).
    pub(crate) fn has(&self, stage: &str, tile: usize) -> bool {
        self.tile_path(stage, tile).is_file()
    }

    /// Saves `tile`'s payload: temporary name, fsync, rename.
    pub(crate) fn save(&self, stage: &str, tile: usize, payload: &[u8]) -> Result<(), StoreError> {
        let dir = self.stage_dir(stage);
        std::fs::create_dir_all(&dir).map_err(|e| StoreError::os(&dir, e))?;
        let path = self.tile_path(stage, tile);
        let mut file = AtomicFile::create(&path)?;
        let header = [
            *MAGIC,
            (payload.len() as u64).to_le_bytes(),
            u64::from(crc32fast::hash(payload)).to_le_bytes(),
        ];
        let write = |f: &mut std::fs::File| -> std::io::Result<()> {
            header.iter().try_for_each(|h| f.write_all(h))?;
            f.write_all(payload)
        };
        write(file.file()).map_err(|e| StoreError::os(&path, e))?;
        Ok(file.commit()?)
    }

    /// How many of `n` tiles of `stage` have a saved result.
    pub(crate) fn count(&self, stage: &str, n: usize) -> usize {
        (0..n).filter(|&t| self.has(stage, t)).count()
    }

    /// Removes temporary files a killed process left (not its tiles).
    pub fn remove_leftovers(&self) -> Result<usize, StoreError> {
        let mut removed = 0;
        let Ok(stages) = std::fs::read_dir(&self.dir) else {
            return Ok(0);
        };
        for stage in stages.flatten() {
            let Ok(files) = std::fs::read_dir(stage.path()) else {
                continue;
            };
            for f in files.flatten() {
                // Anything but a whole tile is a killed writer's temporary.
                if !f.file_name().to_string_lossy().ends_with(".tile") {
                    remove(&f.path())?;
                    removed += 1;
                }
            }
        }
        Ok(removed)
    }

    /// The run directory holding the tile results.
    pub fn dir(&self) -> &Path {
        &self.dir
    }
}

fn remove(path: &Path) -> Result<(), StoreError> {
    std::fs::remove_file(path).map_err(|e| StoreError::os(path, e))
}

/// The payload of a whole tile file.
fn payload(bytes: &[u8]) -> Option<&[u8]> {
    if bytes.len() < HEADER || &bytes[..8] != MAGIC {
        return None;
    }
    let len = u64::from_le_bytes(bytes[8..16].try_into().ok()?);
    let sum = u64::from_le_bytes(bytes[16..24].try_into().ok()?);
    let body = &bytes[HEADER..];
    (body.len() as u64 == len && u64::from(crc32fast::hash(body)) == sum).then_some(body)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tile_sets_read_as_the_scripts_write_them() {
        let range = TileSet::parse_range;
        assert_eq!(range("3-5"), Ok(TileSet::Range { first: 3, last: 5 }));
        assert_eq!(range(" 7 "), Ok(TileSet::Range { first: 7, last: 7 }));
        let backwards = range("5-3").expect_err("backwards");
        assert_eq!(
            backwards.to_string(),
            "5-3: the last tile comes before the first"
        );
        let word = range("x-2").expect_err("a word");
        assert_eq!(word.to_string(), "x-2: invalid digit found in string");
        let share = TileSet::parse_share;
        assert_eq!(share("1/4"), Ok(TileSet::Share { index: 1, count: 4 }));
        let past = share("4/4").expect_err("past the count");
        assert_eq!(past.to_string(), "4/4: INDEX must be below COUNT");
        let bare = share("4").expect_err("no slash");
        assert_eq!(bare.to_string(), "4: expected INDEX/COUNT");
    }

    #[test]
    fn saved_tiles_load_and_damaged_ones_are_dropped() {
        let dir = tempfile::tempdir().unwrap();
        let cp = Checkpoints::new(dir.path(), Job::Whole);
        assert_eq!(cp.load("marching cubes", 3).unwrap(), None);
        cp.save("marching cubes", 3, b"hello tile").unwrap();
        assert_eq!(
            cp.load("marching cubes", 3).unwrap().unwrap(),
            b"hello tile"
        );
        assert_eq!(cp.count("marching cubes", 5), 1);
        let path = dir.path().join("marching-cubes/0000003.tile");
        let mut bytes = std::fs::read(&path).unwrap();
        let last = bytes.len() - 1;
        bytes[last] ^= 1;
        std::fs::write(&path, &bytes).unwrap();
        assert_eq!(cp.load("marching cubes", 3).unwrap(), None);
        assert!(!path.exists(), "a damaged tile file stays");
        assert_eq!(cp.damaged(), vec![path.clone()]);
        std::fs::write(dir.path().join("marching-cubes/0000004.tmp-9"), b"x").unwrap();
        assert_eq!(cp.remove_leftovers().unwrap(), 1);
    }

    #[test]
    fn shares_cover_every_tile_once() {
        for n in [0, 1, 7, 100, 1025] {
            let mut next = 0;
            for index in 0..16 {
                let r = TileSet::Share { index, count: 16 }.tiles(n);
                assert_eq!(r.start, next);
                next = r.end;
            }
            assert_eq!(next, n);
        }
        assert_eq!(TileSet::Range { first: 3, last: 5 }.tiles(4), 3..4);
    }
}
