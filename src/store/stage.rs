//! The tile stages, by a typed id: those a resumable run keeps results of
//! and those run through the stage contract (`pipeline::Stage::ID`). A
//! stage's name is on disk (the directory of its finished tiles, the file
//! of its global result in a run directory) and in the log, progress bars,
//! errors and `status`, so the names are today's exact strings: run
//! directories made by earlier versions resume.

use super::Checkpoints;

/// A tile stage: one whose results a run directory keeps (its tiles, or
/// its global result), or one that runs as a `pipeline::Stage`. A name,
/// so a new stage declares its own id where it lives
/// (`outliers::OUTLIER_SCORES`) and this file does not grow with the
/// stages; the ids of the stages run directories keep are here.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct StageId(&'static str);

impl StageId {
    /// The normals' PCA tiles, and their global report.
    pub const NORMALS: StageId = StageId::new("normals");
    /// The six-sources orientation's tiles (`--orientation sources`).
    pub const ORIENT_SOURCES: StageId = StageId::new("orient: six sources");
    /// The neighbour lists' tiles.
    pub const NEIGHBOURS: StageId = StageId::new("neighbours");
    /// The implicit surface's marching-cubes tiles.
    pub const MARCHING_CUBES: StageId = StageId::new("marching cubes");
    /// The curvature of `curvature` and `features` (no saved tiles).
    pub const CURVATURE: StageId = StageId::new("features: curvature");

    /// The stage named `name`, as kernels, logs, progress bars and
    /// `status` say it; its [`slug`](Self::slug) names its directory.
    pub const fn new(name: &'static str) -> StageId {
        StageId(name)
    }

    /// The stage's name, as kernels, logs and `status` say it.
    pub fn name(self) -> &'static str {
        self.0
    }

    /// The name as a directory and command-line word ("marching-cubes").
    pub fn slug(self) -> String {
        Checkpoints::slug(self.name())
    }
}

impl std::fmt::Display for StageId {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The names are file names in existing run directories.
    #[test]
    fn names_are_those_on_disk() {
        assert_eq!(StageId::NORMALS.name(), "normals");
        assert_eq!(StageId::MARCHING_CUBES.slug(), "marching-cubes");
        assert_eq!(StageId::ORIENT_SOURCES.slug(), "orient--six-sources");
        assert_eq!(StageId::NEIGHBOURS.to_string(), "neighbours");
        // Progress labels and errors as they were.
        assert_eq!(StageId::CURVATURE.name(), "features: curvature");
    }
}
