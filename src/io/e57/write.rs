//! The E57 point writer: one scan of f64 cartesian coordinates in the
//! world frame (identity pose), with intensity and colour as 16-bit
//! integers when asked for (limits 0-65535, so a reader normalising by them
//! gets the values back), streamed through the e57 crate's writer,
//! which buffers one data packet (at most 64 KiB) at a time.
//!
//! As for reading, the crate's scan writer borrows its file writer, so both
//! live on a thread of their own; chunks reach it through a channel of
//! [`AHEAD`]. The file goes through [`AtomicFile`]: it appears under its
//! name only once the XML section and header are written. Normals and
//! per-point flags have no field in standard E57 and are not written.

use super::read::e57_error;
use crate::io::write::check_chunk;
use crate::io::{
    AtomicFile, Attribute, AttributeSet, Attributes, E57Reason, E57Step, IoError, PointChunk,
    PointWriter, WriterSpec,
};
use ::e57::{Record, RecordDataType, RecordName, RecordValue};
use crossbeam::channel::{bounded, Receiver, Sender};
use glam::DVec3;
use std::fs::File;
use std::path::{Path, PathBuf};
use std::thread::JoinHandle;

/// Chunks queued for the writing thread.
const AHEAD: usize = 2;

enum Msg {
    Points(Vec<DVec3>, Attributes),
    /// Write the XML section and header: the file is complete.
    Finish,
}

pub(crate) struct E57Writer {
    path: PathBuf,
    atomic: Option<AtomicFile>,
    to_worker: Option<Sender<Msg>>,
    worker: Option<JoinHandle<Result<(), IoError>>>,
    spec: WriterSpec,
    count: u64,
}

impl E57Writer {
    /// Normals and flags in `spec` are not written (E57 has no field).
    pub fn create(path: &Path, spec: &WriterSpec) -> Result<Self, IoError> {
        let attributes = spec.attributes;
        let mut atomic = AtomicFile::create(path)?;
        let file = atomic
            .file()
            .try_clone()
            .map_err(|e| IoError::os(path, e))?;
        let (tx, rx) = bounded(AHEAD);
        let owned = path.to_path_buf();
        let worker = std::thread::Builder::new()
            .name("e57-write".into())
            .spawn(move || write_scan(&owned, file, attributes, rx))
            .map_err(|e| IoError::os(path, e))?;
        Ok(E57Writer {
            path: path.to_path_buf(),
            atomic: Some(atomic),
            to_worker: Some(tx),
            worker: Some(worker),
            spec: WriterSpec {
                with_normals: false,
                with_flags: false,
                ..spec.clone()
            },
            count: 0,
        })
    }

    /// The worker's error, once it has stopped early.
    fn worker_error(&mut self) -> IoError {
        self.to_worker = None;
        match self.worker.take().map(|w| w.join()) {
            Some(Ok(Err(e))) => e,
            _ => IoError::E57 {
                path: self.path.clone(),
                reason: Box::new(E57Reason::WriterStopped),
            },
        }
    }
}

/// A GUID for the file and its scan: unique enough across runs (time and
/// process), which is all E57 asks of it.
fn guid(kind: &str) -> String {
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos());
    format!("{{scanmesh-{kind}-{:x}-{nanos:x}}}", std::process::id())
}

/// Worker: one scan from the chunks received, finalised on `Finish`; a
/// hang-up without it leaves the file unfinished (the caller drops it).
fn write_scan(
    path: &Path,
    file: File,
    attributes: AttributeSet,
    chunks: Receiver<Msg>,
) -> Result<(), IoError> {
    let err = |what: &'static str| move |e| e57_error(path, E57Step::Named(what), e);
    let mut file57 = ::e57::E57Writer::new(file, &guid("file")).map_err(err("cannot start"))?;
    let mut prototype = vec![
        Record::CARTESIAN_X_F64,
        Record::CARTESIAN_Y_F64,
        Record::CARTESIAN_Z_F64,
    ];
    let u16_record = |name| Record {
        name,
        data_type: RecordDataType::U16,
    };
    if attributes.contains(Attribute::Intensity) {
        prototype.push(Record::INTENSITY_U16);
    }
    if attributes.contains(Attribute::Rgb) {
        prototype.extend(
            [
                RecordName::ColorRed,
                RecordName::ColorGreen,
                RecordName::ColorBlue,
            ]
            .map(u16_record),
        );
    }
    let mut scan = file57
        .add_pointcloud(&guid("scan"), prototype)
        .map_err(err("cannot start the scan"))?;
    scan.set_name(Some("scanmesh".into()));
    for msg in chunks.iter() {
        match msg {
            Msg::Points(pts, attrs) => {
                for (i, p) in pts.iter().enumerate() {
                    let mut values = p.to_array().map(RecordValue::Double).to_vec();
                    let a = attrs.get(i);
                    let int = |v: u16| RecordValue::Integer(i64::from(v));
                    if attributes.contains(Attribute::Intensity) {
                        values.push(int(a.intensity));
                    }
                    if attributes.contains(Attribute::Rgb) {
                        values.extend(a.rgb.map(int));
                    }
                    scan.add_point(values).map_err(err("cannot add a point"))?;
                }
            }
            Msg::Finish => {
                scan.finalize().map_err(err("cannot finish the scan"))?;
                return file57
                    .finalize()
                    .map_err(err("cannot write the XML section"));
            }
        }
    }
    Ok(())
}

impl PointWriter for E57Writer {
    fn write_chunk(&mut self, chunk: &PointChunk, _flags: Option<&[u8]>) -> Result<(), IoError> {
        check_chunk(&self.path, &self.spec, chunk, None, self.count)?;
        let sent = match &self.to_worker {
            // The worker writes the spec's attributes (checked above to be
            // among the chunk's) from the chunk's columns.
            Some(tx) => tx
                .send(Msg::Points(chunk.xyz.clone(), chunk.attrs.clone()))
                .is_ok(),
            None => false,
        };
        if !sent {
            return Err(self.worker_error());
        }
        self.count += chunk.len() as u64;
        Ok(())
    }

    fn finish(mut self: Box<Self>) -> Result<u64, IoError> {
        if let Some(tx) = self.to_worker.take() {
            // A failed send means the worker stopped: its join says why.
            let _ = tx.send(Msg::Finish);
        }
        match self.worker.take().map(|w| w.join()) {
            Some(Ok(Ok(()))) => {}
            Some(Ok(Err(e))) => return Err(e),
            _ => return Err(self.worker_error()),
        }
        crate::io::write::check_count(&self.path, &self.spec, self.count)?;
        if let Some(atomic) = self.atomic.take() {
            atomic.commit()?;
        }
        Ok(self.count)
    }
}

impl Drop for E57Writer {
    fn drop(&mut self) {
        // Hang up so the worker ends without finishing the file, which the
        // AtomicFile then removes.
        self.to_worker = None;
        if let Some(w) = self.worker.take() {
            let _ = w.join();
        }
    }
}
