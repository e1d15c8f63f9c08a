//! The outliers' seam: each tile's scores and flags written to their
//! columns and its order-free sums added up, in tile order; once every
//! tile is in, the rule's threshold from the sums (the same for any
//! tiling) and a second pass over the columns flagging the points past it.

use super::kernel::{Sums, TileScores};
use super::{OutlierParams, OutlierReport, OutliersError, FEWER_THAN_K, OUTLIER};
use crate::pipeline::{PipelineError, RunOptions, RunStats, Seam};
use crate::progress::Progress;
use crate::store::{Column, PointStore};

/// The outliers' seam over a store and its two columns.
pub struct ScoreSeam<'s> {
    pub(super) store: &'s PointStore,
    pub(super) scores: &'s Column,
    pub(super) flags: &'s Column,
    pub(super) sums: Sums,
    pub(super) params: OutlierParams,
}

impl Seam for ScoreSeam<'_> {
    type Tile = TileScores;
    type Report = OutlierReport;
    type Error = OutliersError;

    fn accept(&mut self, tile: usize, out: TileScores) -> Result<(), PipelineError> {
        let start = self.store.tiles()[tile].start;
        self.scores.write_f32(start, &out.scores)?;
        self.flags.write_bytes(start, &out.flags)?;
        self.sums.merge(&out.sums);
        Ok(())
    }

    fn finish(
        self,
        run: RunStats,
        _: RunOptions,
        _: &dyn Progress,
    ) -> Result<OutlierReport, OutliersError> {
        let (sums, params) = (&self.sums, &self.params);
        let mean = sums.score.mean();
        let n = sums.score.count() as f64;
        // The sample variance, as PCL and Open3D take it.
        let variance = (sums.square.mean() - mean * mean) * n / (n - 1.0).max(1.0);
        let std_dev = variance.max(0.0).sqrt();
        let threshold = mean + params.ratio * std_dev;
        let (mut outliers, mut not_judged) = (0, 0);
        let (mut s, mut f) = (Vec::new(), Vec::new());
        for t in self.store.tiles() {
            self.scores.read_f32(t.start, t.count, &mut s)?;
            self.flags.read_u8(t.start, t.count, &mut f)?;
            for (flag, score) in f.iter_mut().zip(&s) {
                if *flag == 0 && f64::from(*score) > threshold {
                    *flag = OUTLIER;
                }
                outliers += u64::from(*flag == OUTLIER);
                not_judged += u64::from(*flag == FEWER_THAN_K);
            }
            self.flags.write_bytes(t.start, &f)?;
        }
        Ok(OutlierReport {
            points: self.store.len(),
            mean,
            std_dev,
            threshold,
            outliers,
            not_judged,
            run,
            params: self.params,
        })
    }
}
