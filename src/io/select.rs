//! What of an input is processed: the points a selection by class and
//! return keeps (`--classes`, `--returns`, as PDAL's range filters select
//! them), and the count of records left out, by why ([`LeftOut`]: pixels
//! of an organised cloud without a return, points not selected).
//!
//! A selection is applied while the input is read (`Selecting` wraps
//! any reader): points not selected never reach a store, so every kernel
//! sees only the selected ones, memory stays what the selected points
//! need, and the store's exact coordinates are the selected points'
//! own. A selection the input cannot answer (classes of a file without
//! classification, last returns of a file without numbers of returns) is
//! an error naming the file, never an empty or a whole selection.

use super::{Attribute, Attributes, Format, IoError, PointChunk, PointReader, SourceInfo};
use serde::{Deserialize, Serialize};

/// Records of an input that hold no point to process, by why; each
/// count is of input records, none of them in a store or a per-point
/// output that drops them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct LeftOut {
    /// Pixels of an organised cloud (PCD with `HEIGHT` > 1) whose
    /// coordinates are NaN: the sensor saw nothing there.
    pub no_return: u64,
    /// Points a class or return selection did not select.
    pub unselected: u64,
}

impl LeftOut {
    /// All records left out.
    pub fn total(&self) -> u64 {
        self.no_return + self.unselected
    }

    /// The sum of two counts.
    pub fn plus(self, o: LeftOut) -> LeftOut {
        LeftOut {
            no_return: self.no_return + o.no_return,
            unselected: self.unselected + o.unselected,
        }
    }

    /// The counts in words ("" when nothing was left out).
    pub fn describe(&self) -> String {
        let mut parts = Vec::new();
        if self.no_return > 0 {
            parts.push(format!(
                "{} without a return (NaN pixels of an organised cloud)",
                self.no_return
            ));
        }
        if self.unselected > 0 {
            parts.push(format!("{} not selected", self.unselected));
        }
        parts.join(", ")
    }
}

/// Which returns of a multi-return pulse to keep (the CLI's `--returns`).
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize, clap::ValueEnum,
)]
#[serde(rename_all = "snake_case")]
pub enum Returns {
    /// Every return.
    #[default]
    All,
    /// Return number 1.
    First,
    /// Return number equal to the pulse's number of returns (LAS/LAZ).
    #[value(help = "Return number equal to the pulse's number of returns")]
    Last,
}

/// Which points of an input to process: by classification code and by
/// return. The default selects every point.
#[derive(Clone, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct Selection {
    /// Classification codes to keep (`None`: every class).
    pub classes: Option<Vec<u8>>,
    /// Returns to keep.
    pub returns: Returns,
}

impl Selection {
    /// Whether the selection keeps every point.
    pub fn is_all(&self) -> bool {
        self.classes.is_none() && self.returns == Returns::All
    }

    /// The selection in words, as the summary line and errors say it.
    pub fn describe(&self) -> String {
        let mut parts = Vec::new();
        if let Some(c) = &self.classes {
            let c: Vec<String> = c.iter().map(u8::to_string).collect();
            parts.push(format!("classes {}", c.join(",")));
        }
        match self.returns {
            Returns::All => {}
            Returns::First => parts.push("first returns".into()),
            Returns::Last => parts.push("last returns".into()),
        }
        match parts.is_empty() {
            true => "every point".into(),
            false => parts.join(", "),
        }
    }

    /// Why `info`'s input cannot answer this selection, if it cannot.
    fn refusal(&self, info: &SourceInfo) -> Option<String> {
        let holds = |a| info.attributes.contains(a);
        if self.classes.is_some() && !holds(Attribute::Classification) {
            return Some(format!(
                "a class selection needs each point's classification, and this {} file holds none",
                format_name(info.format)
            ));
        }
        let las = matches!(info.format, Format::Las | Format::Laz);
        match self.returns {
            Returns::First if !holds(Attribute::ReturnNumber) => Some(format!(
                "a return selection needs each point's return number, and this {} file holds none",
                format_name(info.format)
            )),
            Returns::Last if !las => Some(format!(
                "last returns need each point's number of returns, which only LAS/LAZ hold, not this {} file",
                format_name(info.format)
            )),
            _ => None,
        }
    }
}

fn format_name(f: Format) -> &'static str {
    match f {
        Format::PlyAscii | Format::PlyBinaryLe | Format::PlyBinaryBe => "PLY",
        Format::Xyz => "XYZ/CSV",
        Format::Las => "LAS",
        Format::Laz => "LAZ",
        Format::Pcd => "PCD",
        Format::E57 => "E57",
    }
}

/// A reader handing out only the points `selection` keeps, counting the
/// others ([`LeftOut::unselected`]); input indices stay those of the file.
pub(crate) struct Selecting {
    inner: Box<dyn PointReader>,
    selector: Selector,
    unselected: u64,
    keep: Vec<bool>,
}

/// A [`Selection`] ready to test points: classes as a table.
#[derive(Clone, Copy)]
pub(crate) struct Selector {
    classes: Option<[bool; 256]>,
    returns: Returns,
}

impl Selector {
    pub(crate) fn new(selection: &Selection) -> Self {
        let classes = selection.classes.as_ref().map(|c| {
            let mut set = [false; 256];
            c.iter().for_each(|&k| set[usize::from(k)] = true);
            set
        });
        Selector {
            classes,
            returns: selection.returns,
        }
    }

    /// Whether point `i` of `chunk` is selected (the chunk carries what
    /// the selection reads: checked by [`Selecting::wrap`]).
    pub(crate) fn selects(&self, chunk: &PointChunk, i: usize) -> bool {
        let a = &chunk.attrs;
        let class_ok = self
            .classes
            .is_none_or(|set| set[usize::from(a.classification[i])]);
        class_ok
            && match self.returns {
                Returns::All => true,
                Returns::First => a.return_number[i] == 1,
                // LAS only (checked when wrapped): the reader fills the counts.
                Returns::Last => chunk.number_of_returns.get(i) == Some(&a.return_number[i]),
            }
    }
}

impl Selecting {
    /// `inner` read through `selection`, or the error that `inner`'s
    /// file cannot answer it.
    pub(crate) fn wrap(
        inner: Box<dyn PointReader>,
        selection: &Selection,
    ) -> Result<Box<dyn PointReader>, IoError> {
        if selection.is_all() {
            return Ok(inner);
        }
        if let Some(reason) = selection.refusal(inner.info()) {
            return Err(IoError::Unsupported {
                path: inner.info().path.clone(),
                reason,
            });
        }
        Ok(Box::new(Selecting {
            inner,
            selector: Selector::new(selection),
            unselected: 0,
            keep: Vec::new(),
        }))
    }
}

impl PointReader for Selecting {
    fn info(&self) -> &SourceInfo {
        self.inner.info()
    }

    /// Reads the inner reader's chunks until one holds a selected point
    /// (each one cleared before the next, so memory stays a chunk's).
    fn read_chunk(&mut self, chunk: &mut PointChunk, max: usize) -> Result<usize, IoError> {
        loop {
            if self.inner.read_chunk(chunk, max)? == 0 {
                return Ok(0);
            }
            let mut keep = std::mem::take(&mut self.keep);
            keep.clear();
            keep.extend((0..chunk.len()).map(|i| self.selector.selects(chunk, i)));
            let kept = keep.iter().filter(|&&k| k).count();
            self.unselected += (chunk.len() - kept) as u64;
            retain(chunk, &keep);
            self.keep = keep;
            if kept > 0 {
                return Ok(kept);
            }
        }
    }

    fn skipped(&self) -> u64 {
        self.inner.skipped()
    }

    fn left_out(&self) -> LeftOut {
        self.inner.left_out().plus(LeftOut {
            no_return: 0,
            unselected: self.unselected,
        })
    }

    /// The inner reader's stations: they are runs of input records, which
    /// a selection keeps their numbers.
    fn stations(&self) -> Vec<super::ScanStation> {
        self.inner.stations()
    }
}

/// Keeps the points of `chunk` whose `keep` is true, with their indices.
fn retain(chunk: &mut PointChunk, keep: &[bool]) {
    if keep.iter().all(|&k| k) {
        return;
    }
    let indices: Vec<u64> = (0..chunk.len())
        .filter(|&i| keep[i])
        .map(|i| chunk.index_of(i))
        .collect();
    retain_vec(&mut chunk.xyz, keep);
    if let Some(n) = &mut chunk.normals {
        retain_vec(n, keep);
    }
    retain_vec(&mut chunk.number_of_returns, keep);
    chunk.attrs.retain(keep);
    if let Some(&first) = indices.first() {
        chunk.first_index = first;
    }
    chunk.indices = Some(indices);
}

/// Keeps `v[i]` where `keep[i]`; a column shorter than `keep` (one the
/// chunk does not carry) stays as it is.
fn retain_vec<T>(v: &mut Vec<T>, keep: &[bool]) {
    if v.len() != keep.len() {
        return;
    }
    let mut k = keep.iter();
    v.retain(|_| *k.next().unwrap_or(&true));
}

impl Attributes {
    /// Keeps the values of the points whose `keep` is true, in every
    /// column the set holds (a column added to [`Attributes`] must be
    /// kept here too).
    pub(crate) fn retain(&mut self, keep: &[bool]) {
        retain_vec(&mut self.intensity, keep);
        retain_vec(&mut self.rgb, keep);
        retain_vec(&mut self.classification, keep);
        retain_vec(&mut self.return_number, keep);
        retain_vec(&mut self.gps_time, keep);
        self.las.retain(keep);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::memory::MemoryReader;
    use crate::io::{AttributeSet, AttributeValues};
    use glam::DVec3;

    /// Points 0..n with class `i % 7`, return `i % 3 + 1` of `(i % 3) + 1 + i % 2`.
    fn chunk_of(n: usize) -> PointChunk {
        let mut c = PointChunk::default();
        c.attrs.reset(AttributeSet::of(&[
            Attribute::Classification,
            Attribute::ReturnNumber,
        ]));
        for i in 0..n {
            c.xyz.push(DVec3::splat(i as f64));
            let r = (i % 3) as u8 + 1;
            c.attrs.push(&AttributeValues {
                classification: (i % 7) as u8,
                return_number: r,
                ..Default::default()
            });
            c.number_of_returns.push(r + (i % 2) as u8);
        }
        c
    }

    #[test]
    fn retain_keeps_indices_and_every_column() {
        let mut c = chunk_of(10);
        let keep: Vec<bool> = (0..10).map(|i| i % 4 == 1).collect();
        retain(&mut c, &keep);
        assert_eq!(c.xyz, [1.0, 5.0, 9.0].map(DVec3::splat));
        assert_eq!(c.indices, Some(vec![1, 5, 9]));
        assert_eq!(c.first_index, 1);
        assert_eq!(c.attrs.classification, [1, 5, 2]);
        assert_eq!(c.number_of_returns, [3, 4, 1 + 1]);
    }

    #[test]
    fn a_selection_the_file_cannot_answer_names_it() {
        let pts = vec![DVec3::ZERO; 3];
        let r = Box::new(MemoryReader::new("cloud.xyz", pts, None));
        let sel = Selection {
            classes: Some(vec![2]),
            returns: Returns::All,
        };
        let err = Selecting::wrap(r, &sel).err().expect("refused").to_string();
        assert!(
            err.contains("cloud.xyz") && err.contains("classification"),
            "{err}"
        );
    }

    #[test]
    fn describe_says_what_is_selected_and_left_out() {
        let sel = Selection {
            classes: Some(vec![2, 6]),
            returns: Returns::Last,
        };
        assert_eq!(sel.describe(), "classes 2,6, last returns");
        let l = LeftOut {
            no_return: 3,
            unselected: 4,
        };
        assert_eq!(l.total(), 7);
        assert!(l.describe().contains("3 without a return"));
    }
}
