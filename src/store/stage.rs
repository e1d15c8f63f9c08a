//! The tile stages, by a typed id: those a resumable run keeps results of
//! and those run through the stage contract (`pipeline::Stage::ID`). A
//! stage's name is on disk (the directory of its finished tiles, the file
//! of its global result in a run directory) and in the log, progress bars,
//! errors and `status`, so the names are today's exact strings: run
//! directories made by earlier versions resume.

use super::Checkpoints;

/// A tile stage: one whose results a run directory keeps (its tiles, or
/// its global result), or one that runs as a `pipeline::Stage`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum StageId {
    /// The normals' PCA tiles, and their global report.
    Normals,
    /// The six-sources orientation's tiles (`--orientation sources`).
    OrientSources,
    /// The neighbour lists' tiles.
    Neighbours,
    /// The implicit surface's marching-cubes tiles.
    MarchingCubes,
    /// The outlier scores (`outliers`; no saved tiles).
    OutlierScores,
    /// The curvature of `curvature` and `features` (no saved tiles).
    Curvature,
}

impl StageId {
    /// The stage's name, as kernels, logs and `status` say it.
    pub fn name(self) -> &'static str {
        match self {
            StageId::Normals => "normals",
            StageId::OrientSources => "orient: six sources",
            StageId::Neighbours => "neighbours",
            StageId::MarchingCubes => "marching cubes",
            StageId::OutlierScores => "outlier scores",
            StageId::Curvature => "features: curvature",
        }
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
        assert_eq!(StageId::Normals.name(), "normals");
        assert_eq!(StageId::MarchingCubes.slug(), "marching-cubes");
        assert_eq!(StageId::OrientSources.slug(), "orient--six-sources");
        assert_eq!(StageId::Neighbours.to_string(), "neighbours");
        // Progress labels and errors as they were.
        assert_eq!(StageId::OutlierScores.name(), "outlier scores");
        assert_eq!(StageId::Curvature.name(), "features: curvature");
    }
}
