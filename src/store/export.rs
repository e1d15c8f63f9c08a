//! Writing a store's points (and normals, flags) in input order to any point
//! format. Coordinates and attributes are the input's own, exactly as read
//! (`super::exact`), read a window at a time from their input-order
//! columns, or from the input itself when the store keeps nothing of it
//! (`super::reread`, checked against the build's checksums); only the
//! computed columns (normals, flags) are in tile order.
//! Tiles are in spatial order, the output is in input order: the export
//! fills windows of consecutive input indices, each by one pass over the
//! tiles, so memory is one window plus one tile per thread whatever the
//! store size. A LAS output of a LAS input is written as the input came:
//! its own records (read from the store's `las.input` like any input-order
//! column), version, point format, scale, offset, VLRs and EVLRs, the
//! normals and flags appended as extra bytes (`crate::io::LasOutput`).
//! Any other output of a LAS input whose colour channels are all at most
//! 255 gets that colour widened to 16 bits first (8-bit colour in 16-bit
//! fields, as PDAL reads it), so 8-bit formats do not write it black.
//!
//! A window is split into one id range per thread; each thread passes over
//! the tiles and places the points of its range. The placement is a random
//! write per point (scans come in scanner order, tiles in spatial order), so
//! it is the costly part and the one that divides; every slot is written by
//! exactly one point, so the result does not depend on the threads.
//!
//! With more than one window, a pass per window would read the whole store
//! once per window (15 times for 10M points in 256 MiB, n^2 / memory in
//! general); the points are then first sorted into their windows' regions
//! of a scratch file (`super::reorder`) and each window read back from it.

use super::reorder::Reorder;
use super::reread::Reread;
use super::slots::{Columns, Slots, TileValues};
use super::{ColumnSpec, Item, Kept, PointStore, StoreError, FLAGS, NORMALS};
use crate::io::{
    create_writer_with, Attribute, Format, LasOutput, PointChunk, PointWriter, WriterSpec,
};
use crate::progress::Progress;
use crossbeam::channel::{bounded, Receiver, Sender};
use glam::{DVec3, Vec3};
use rayon::prelude::*;
use std::path::Path;

/// Where an input-order export writes and how it is paced.
#[derive(Clone, Copy)]
pub struct Rows<'a> {
    /// The output file.
    pub output: &'a Path,
    /// Points per window (the memory plan's `window_points`).
    pub window: u64,
    /// The input file the store was built from and how it was read: a
    /// store that keeps nothing of its input ([`super::Kept::Nothing`])
    /// has its points' coordinates, attributes and records read from it
    /// again (`super::reread`); `None`: the store's own.
    pub input: Option<(&'a Path, &'a crate::io::ReadOptions)>,
    /// Write the input's points the read's selection left out of the
    /// store between the others, flagged ([`crate::io::keep`]); needs
    /// `input`.
    pub keep_unselected: bool,
    /// Progress bars, or none.
    pub progress: &'a dyn Progress,
}

/// Writes `store` to `path` in input order; returns the points written.
pub fn export_points(
    store: &PointStore,
    path: &Path,
    spec: &WriterSpec,
    window: u64,
    progress: &dyn Progress,
) -> Result<u64, StoreError> {
    let rows = Rows {
        output: path,
        window,
        input: None,
        keep_unselected: false,
        progress,
    };
    export_points_keeping(store, spec, &rows)
}

/// [`export_points`] to `rows`, with the points `rows.keep_unselected`
/// asks for; returns the rows written.
pub fn export_points_keeping(
    store: &PointStore,
    spec: &WriterSpec,
    rows: &Rows,
) -> Result<u64, StoreError> {
    export_columns(store, spec, &Computed::normals_for(spec), rows)
}

/// The store's computed columns an export writes beside the points: the
/// normals, the values ([`WriterSpec::values`], one f32 of the column each)
/// and the flags, each present exactly when the spec asks for it.
#[derive(Clone, Copy, Debug, Default)]
pub struct Computed {
    /// The column of normals (3 x f32).
    pub normals: Option<ColumnSpec>,
    /// The column of values (as many f32 as the spec names).
    pub values: Option<ColumnSpec>,
    /// The column of flags (u8).
    pub flags: Option<ColumnSpec>,
}

impl Computed {
    /// The normals pass's columns ([`NORMALS`], [`FLAGS`]), as `spec`
    /// asks for them.
    pub fn normals_for(spec: &WriterSpec) -> Self {
        Computed {
            normals: spec.with_normals.then_some(NORMALS),
            values: None,
            flags: spec.with_flags.then_some(FLAGS),
        }
    }

    /// Opens the columns, checked against what `spec` asks to write.
    fn open(&self, store: &PointStore, spec: &WriterSpec) -> Result<Columns, StoreError> {
        let per_point = spec.values.len();
        let fits = self.normals.is_some() == spec.with_normals
            && self.flags.is_some() == spec.with_flags
            && match self.values {
                Some(c) => c.item == Item::F32(per_point),
                None => per_point == 0,
            };
        if !fits {
            return Err(StoreError::Corrupt {
                path: store.dir().to_path_buf(),
                reason: format!(
                    "the export's columns ({self:?}) are not what its output asks for \
                     (normals {}, {per_point} values, flags {})",
                    spec.with_normals, spec.with_flags
                ),
            });
        }
        let open = |c: Option<ColumnSpec>| c.map(|c| store.column(&c)).transpose();
        Ok(Columns {
            normals: open(self.normals)?,
            values: open(self.values)?,
            per_point,
            flags: open(self.flags)?,
        })
    }
}

/// Writes `store` to `path` in input order with a column of values (as
/// many per point as `spec.values` names) and one of flags, the rows
/// declared before the first (the unselected ones too, when kept), so a short
/// output fails before it is renamed into place: the curvature's and the
/// outliers' output. Returns the rows written.
pub fn export_values(
    store: &PointStore,
    spec: &WriterSpec,
    columns: [ColumnSpec; 2],
    rows: &Rows,
) -> Result<u64, StoreError> {
    let unselected = match rows.input.filter(|_| rows.keep_unselected) {
        Some(_) => store.manifest().left_out.unselected,
        None => 0,
    };
    let spec = WriterSpec {
        count: Some(store.len() + unselected),
        ..spec.clone()
    };
    let [values, flags] = columns;
    let computed = Computed {
        normals: None,
        values: Some(values),
        flags: Some(flags),
    };
    export_columns(store, &spec, &computed, rows)
}

/// Writes `store` to `rows` in input order with the `computed` columns
/// `spec` names, and the rows `rows.keep_unselected` asks for as
/// [`export_points_keeping`] does; returns the rows written.
pub fn export_columns(
    store: &PointStore,
    spec: &WriterSpec,
    computed: &Computed,
    rows: &Rows,
) -> Result<u64, StoreError> {
    let Rows {
        output: path,
        window: window_points,
        input,
        keep_unselected,
        progress,
    } = *rows;
    let keep = input.filter(|_| keep_unselected);
    let cols = computed.open(store, spec)?;
    let mut spec = spec.clone();
    if spec.las_transform.is_none() {
        spec.las_transform = store.coordinates().las_transform();
    }
    if spec.bounds.is_none() {
        spec.bounds = Some(crate::geom::Aabb::new(
            DVec3::from_array(store.manifest.bounds_min),
            DVec3::from_array(store.manifest.bounds_max),
        ));
    }
    let las_out = matches!(spec.format, Format::Las | Format::Laz);
    let las = LasOutput {
        source: match las_out {
            true => store.las_source()?.map(std::sync::Arc::new),
            false => None,
        },
        point_format: None,
        largest: store.manifest.maxima,
    };
    let records = las.source.is_some();
    let widen = store.manifest.las.is_some()
        && !las_out
        && spec.attributes.contains(Attribute::Rgb)
        && store.manifest.maxima.is_some_and(|m| m.eight_bit_colour());
    let mut writer = create_writer_with(path, &spec, &las)?;
    if let Some((input, read)) = keep {
        writer = Box::new(crate::io::keep::KeepUnselected::wrap(
            writer, path, input, read, &spec,
        )?);
    }
    let n = store.len();
    let record_bytes = match (records, store.manifest.las) {
        (true, Some(l)) => u64::from(l.record_len),
        _ => 0,
    };
    // Two windows of half the size: one filled while the other is written.
    let extra_bytes = record_bytes + 4 * spec.values.len() as u64;
    let window =
        (attribute_window(window_points, spec.attributes, extra_bytes) / 2).clamp(1, n.max(1));
    progress.begin("write", n);
    let buckets = if window < n && cols.any() {
        Some(Reorder::build(store, &cols, window)?)
    } else {
        None
    };
    let mut source = InputRows::open(store, input)?;
    let (full_tx, full_rx) = bounded::<Window>(1);
    let (empty_tx, empty_rx) = bounded::<Window>(2);
    for _ in 0..2 {
        let _ = empty_tx.send(Window::default());
    }
    let (filled, writer) = std::thread::scope(|s| {
        let with_flags = cols.flags.is_some();
        let writing =
            s.spawn(move || write_windows(writer, with_flags, full_rx, empty_tx, progress));
        let fill = Fill {
            cols: &cols,
            buckets: buckets.as_ref(),
            attributes: spec.attributes,
            records,
            widen,
            window,
        };
        let filled = fill_windows(store, &fill, &mut source, empty_rx, full_tx);
        (filled, writing.join())
    });
    progress.end();
    // A writer's error explains a fill that stopped because it hung up.
    let writer = match writer {
        Ok(w) => w?,
        Err(panic) => std::panic::resume_unwind(panic),
    };
    filled?;
    // The input read again ends where the store does, or nothing is written.
    source.finish()?;
    Ok(writer.finish()?)
}

/// One window of output points and their flags.
#[derive(Default)]
struct Window {
    chunk: PointChunk,
    flags: Vec<u8>,
}

/// Bytes per point of an export window the plan assumes (positions,
/// normal, flags and encoding); the input's attributes come on top.
const WINDOW_BYTES_PER_POINT: u64 = 48;

/// Points of a window planned at `window_points` without attributes, shrunk
/// so that a window carrying `attributes` and `extra_bytes` more a point
/// (LAS records, computed values) takes no more memory.
fn attribute_window(
    window_points: u64,
    attributes: crate::io::AttributeSet,
    extra_bytes: u64,
) -> u64 {
    let extra = attributes.bytes_per_point() as u64 + extra_bytes;
    window_points * WINDOW_BYTES_PER_POINT / (WINDOW_BYTES_PER_POINT + extra)
}

/// What the windows are filled from.
struct Fill<'a> {
    cols: &'a Columns,
    buckets: Option<&'a Reorder>,
    attributes: crate::io::AttributeSet,
    /// Whether the output is written from the LAS input's own records.
    records: bool,
    /// Whether the colour is 8-bit in 16-bit fields, widened for output.
    widen: bool,
    window: u64,
}

/// Fills consecutive windows of `window` input ids, each in a buffer that
/// comes back on `empty`, and sends it on `full` to be written.
fn fill_windows(
    store: &PointStore,
    fill: &Fill,
    source: &mut InputRows,
    empty: Receiver<Window>,
    full: Sender<Window>,
) -> Result<(), StoreError> {
    let (cols, buckets, window) = (fill.cols, fill.buckets, fill.window);
    let n = store.len();
    let mut w0 = 0;
    while w0 < n {
        let Ok(mut win) = empty.recv() else {
            return Err(writer_gone());
        };
        let len = ((w0 + window).min(n) - w0) as usize;
        let chunk = &mut win.chunk;
        chunk.first_index = w0;
        source.fill(store, w0, len, chunk, fill)?;
        match (&cols.normals, &mut chunk.normals) {
            (Some(_), Some(ns)) => {
                ns.clear();
                ns.resize(len, Vec3::ZERO);
            }
            (Some(_), None) => chunk.normals = Some(vec![Vec3::ZERO; len]),
            (None, _) => chunk.normals = None,
        }
        win.flags.clear();
        win.flags
            .resize(if cols.flags.is_some() { len } else { 0 }, 0);
        chunk.values.clear();
        chunk.values.resize(
            match cols.values {
                Some(_) => len * cols.per_point,
                None => 0,
            },
            0.0,
        );
        let slots = Slots {
            first: w0,
            len,
            normals: chunk.normals.as_deref_mut(),
            values: cols.values.as_ref().map(|_| chunk.values.as_mut_slice()),
            per_point: cols.per_point,
            flags: cols.flags.as_ref().map(|_| win.flags.as_mut_slice()),
        };
        match (buckets, cols.any()) {
            (_, false) => {}
            (Some(b), true) => b.fill(slots)?,
            (None, true) => fill_window(store, cols, slots)?,
        }
        if fill.widen {
            chunk.attrs.widen_8bit_colour();
        }
        if full.send(win).is_err() {
            return Err(writer_gone());
        }
        w0 += len as u64;
    }
    Ok(())
}

/// Where a window's coordinates, attributes and LAS records come from:
/// in input order already, so read, not placed.
enum InputRows {
    /// The store's input-order columns.
    Store,
    /// The input itself, read again (a store that keeps nothing of it).
    Reread(Box<Reread>),
}

impl InputRows {
    fn open(
        store: &PointStore,
        input: Option<(&Path, &crate::io::ReadOptions)>,
    ) -> Result<Self, StoreError> {
        match (store.kept(), input) {
            (Kept::Nothing, Some((path, read))) => Ok(InputRows::Reread(Box::new(Reread::open(
                store, path, read,
            )?))),
            // A store that keeps nothing, not given its input, says so.
            _ => Ok(InputRows::Store),
        }
    }

    /// Fills `chunk` with the points of input ranks `[w0, w0 + len)`.
    fn fill(
        &mut self,
        store: &PointStore,
        w0: u64,
        len: usize,
        chunk: &mut PointChunk,
        fill: &Fill,
    ) -> Result<(), StoreError> {
        match self {
            InputRows::Store => {
                store.read_exact(w0, len as u64, &mut chunk.xyz)?;
                store.read_attributes(w0, len as u64, fill.attributes, &mut chunk.attrs)?;
                if fill.records {
                    store.read_las_records(w0, len as u64, &mut chunk.attrs.las)?;
                }
                Ok(())
            }
            InputRows::Reread(r) => {
                chunk.xyz.clear();
                chunk.attrs.reset(fill.attributes);
                r.next(len, chunk, fill.records)
            }
        }
    }

    fn finish(self) -> Result<(), StoreError> {
        match self {
            InputRows::Store => Ok(()),
            InputRows::Reread(r) => r.finish(),
        }
    }
}

/// Writes the windows arriving on `full` in order, handing each buffer
/// back on `empty`; returns the writer to be finished once every window
/// was filled.
fn write_windows(
    mut writer: Box<dyn PointWriter>,
    with_flags: bool,
    full: Receiver<Window>,
    empty: Sender<Window>,
    progress: &dyn Progress,
) -> Result<Box<dyn PointWriter>, StoreError> {
    for win in full.iter() {
        let flags = with_flags.then_some(win.flags.as_slice());
        writer.write_chunk(&win.chunk, flags)?;
        progress.advance(win.chunk.len() as u64);
        // The filler may have stopped (an error); it reports why.
        let _ = empty.send(win);
    }
    Ok(writer)
}

fn writer_gone() -> StoreError {
    StoreError::Corrupt {
        path: "output".into(),
        reason: "the output writer stopped".into(),
    }
}

/// Fills every slot of a window, one id range per thread.
fn fill_window(store: &PointStore, cols: &Columns, slots: Slots) -> Result<(), StoreError> {
    slots
        .split(rayon::current_num_threads())
        .into_par_iter()
        .try_for_each(|part| fill_part(store, cols, part))
}

/// Places the points whose input ids fall in `part`, passing over all tiles.
fn fill_part(store: &PointStore, cols: &Columns, mut part: Slots) -> Result<(), StoreError> {
    let range = part.range();
    let (mut ids, mut tv) = (Vec::new(), TileValues::default());
    for t in store.tiles() {
        store.read_indices(t.start, t.count, &mut ids)?;
        if !ids.iter().any(|i| range.contains(i)) {
            continue;
        }
        cols.read(t, &mut tv)?;
        for (k, &id) in ids.iter().enumerate() {
            if !range.contains(&id) {
                continue;
            }
            let (normal, values, f) = tv.of(k, cols.per_point);
            let slot = (id - range.start) as usize;
            part.place(slot, &normal, values, f);
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::{open_reader, Format, InvalidPolicy};
    use crate::store::{build_store, BuildOptions, TileTarget};

    /// A normal and a flag that name the input id, to check placement.
    fn normal_of(id: u64) -> [f32; 3] {
        [id as f32, -(id as f32) * 0.5, 1.0]
    }

    #[test]
    fn every_window_and_thread_count_writes_input_order() {
        let mut rng = crate::rng::Rng::new(17);
        let pts: Vec<DVec3> = (0..5003)
            .map(|_| DVec3::from_array([0; 3].map(|_| rng.below(1 << 20) as f64 * 1e-3 + 4e5)))
            .collect();
        let dir = tempfile::tempdir().unwrap();
        let mut reader = crate::io::memory::MemoryReader::new("pts", pts.clone(), None);
        let opts = BuildOptions {
            tiles: TileTarget::Points(600),
            ..BuildOptions::default()
        };
        let nop = &crate::progress::NoProgress;
        let mut store = build_store(&mut reader, &dir.path().join("s"), &opts, nop).unwrap();
        assert!(store.tiles().len() > 4);
        let normals = store.create_column(&NORMALS).unwrap();
        let flags = store.create_column(&FLAGS).unwrap();
        let mut ids = Vec::new();
        for t in store.tiles() {
            store.read_indices(t.start, t.count, &mut ids).unwrap();
            let n: Vec<f32> = ids.iter().flat_map(|&i| normal_of(i)).collect();
            let f: Vec<u8> = ids.iter().map(|&i| (i % 251) as u8).collect();
            normals.write_f32(t.start, &n).unwrap();
            flags.write_bytes(t.start, &f).unwrap();
        }
        let spec = WriterSpec {
            with_normals: true,
            with_flags: true,
            ..WriterSpec::new(Format::PlyBinaryLe)
        };
        let mut first: Option<Vec<u8>> = None;
        for (threads, window) in [(1, 5003), (2, 1), (3, 777), (2, 5003), (4, 64)] {
            let out = dir.path().join(format!("o{threads}_{window}.ply"));
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let written = pool
                .install(|| export_points(&store, &out, &spec, window, nop))
                .unwrap();
            assert_eq!(written, pts.len() as u64);
            let mut r = open_reader(&out, InvalidPolicy::Reject).unwrap();
            let mut chunk = PointChunk::default();
            let n = r.read_chunk(&mut chunk, 1 << 20).unwrap();
            assert_eq!(n, pts.len(), "threads {threads}, window {window}");
            for (i, p) in pts.iter().enumerate() {
                assert_eq!(
                    chunk.xyz[i], *p,
                    "threads {threads}, window {window}, point {i}"
                );
                let got = chunk.normals.as_ref().unwrap()[i].to_array();
                assert_eq!(
                    got,
                    normal_of(i as u64),
                    "threads {threads}, window {window}, point {i}"
                );
            }
            let bytes = std::fs::read(&out).unwrap();
            match &first {
                None => first = Some(bytes),
                Some(b) => assert!(
                    *b == bytes,
                    "threads {threads}, window {window}: bytes differ"
                ),
            }
        }
        // Flags: the last byte of each 37-byte record.
        let bytes = first.unwrap();
        let body = &bytes[bytes.len() - 37 * pts.len()..];
        for (i, rec) in body.chunks_exact(37).enumerate() {
            assert_eq!(rec[36], (i % 251) as u8, "flag of point {i}");
        }
    }
}
