//! LAS/LAZ kept whole (issue 38): `convert` and `normals` write a LAS input
//! as it came, for LAS 1.2, 1.3 and 1.4 and every point format they hold
//! (0-10): the version, point format, scale and offset, every standard
//! field of every point, the extra bytes and every VLR and EVLR (CRS first)
//! equal, the coordinates' integers equal, the normals and flags appended
//! as described extra bytes. Read back with the `las` crate (not
//! scanmesh's reader), field by field; `laspy_reads_every_field_back` does
//! the same with laspy, an independent reader, when python3 has it.

use las::point::{Classification, Format, ScanDirection};
use las::raw::point::Waveform;
use las::{Builder, Color, Point, Reader, Transform, Vector, Version, Vlr, Writer};
use std::path::{Path, PathBuf};
use std::process::Command;

fn scanmesh(args: &[&str]) -> std::process::Output {
    let out = Command::new(env!("CARGO_BIN_EXE_scanmesh"))
        .args(args)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "scanmesh {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// An Extra Bytes VLR describing a u8 and an i16 (3 bytes), with names.
fn extra_bytes_vlr() -> Vlr {
    let mut data = vec![0u8; 2 * 192];
    for (d, (t, name)) in data.chunks_exact_mut(192).zip([(1u8, "Amp"), (4, "Dev")]) {
        d[2] = t;
        d[4..4 + name.len()].copy_from_slice(name.as_bytes());
    }
    Vlr {
        user_id: "LASF_Spec".into(),
        record_id: 4,
        description: "Extra Bytes Record".into(),
        data,
    }
}

fn wkt_vlr() -> Vlr {
    Vlr {
        user_id: "LASF_Projection".into(),
        record_id: 2112,
        description: "OGC WKT".into(),
        data: b"PROJCS[\"NAD83 / UTM zone 10N\",GEOGCS[\"NAD83\"],UNIT[\"metre\",1]]\0".to_vec(),
    }
}

fn geotiff_vlr() -> Vlr {
    // GeoKeyDirectory: version 1.1.0, one key: ProjectedCSTypeGeoKey 26910.
    let keys: [u16; 8] = [1, 1, 0, 1, 3072, 0, 1, 26910];
    Vlr {
        user_id: "LASF_Projection".into(),
        record_id: 34735,
        description: "GeoTIFF GeoKeyDirectoryTag".into(),
        data: keys.iter().flat_map(|k| k.to_le_bytes()).collect(),
    }
}

/// A LAS file of `version` and point `format` with `n` points on a gently
/// curved sheet (normals need neighbourhoods), every field set and varied
/// over its legal range, 3 extra bytes, CRS VLRs and (LAS 1.4) an EVLR.
fn synthetic(path: &Path, version: (u8, u8), format: u8, n: usize) {
    let mut f = Format::new(format).unwrap();
    f.extra_bytes = 3;
    let mut b = Builder::from(Version::new(version.0, version.1));
    b.point_format = f;
    b.transforms = Vector {
        x: Transform {
            scale: 0.001,
            offset: 512_000.0,
        },
        y: Transform {
            scale: 0.001,
            offset: 5_403_000.0,
        },
        z: Transform {
            scale: 0.0025,
            offset: -10.0,
        },
    };
    b.system_identifier = "synthetic".into();
    b.generating_software = "las_kept test".into();
    if version.1 >= 4 {
        b.vlrs = vec![wkt_vlr(), extra_bytes_vlr()];
        b.has_wkt_crs = true;
        b.evlrs = vec![Vlr {
            user_id: "test_user".into(),
            record_id: 77,
            description: "an EVLR kept whole".into(),
            data: (0..300u32).map(|i| (i * 7) as u8).collect(),
        }];
    } else {
        b.vlrs = vec![geotiff_vlr(), extra_bytes_vlr()];
    }
    let header = b.into_header().unwrap();
    let mut w = Writer::from_path(path, header).unwrap();
    let side = (n as f64).sqrt().ceil() as usize;
    let extended = format >= 6;
    for i in 0..n {
        let (u, v) = ((i % side) as f64, (i / side) as f64);
        let max_ret = if extended { 15 } else { 5 };
        let nret = (i % max_ret as usize) as u8 + 1;
        let class = match extended {
            true => (i * 37 % 256) as u8,
            false => (i * 7 % 32) as u8,
        };
        let wide = i % 3 == 0;
        let p = Point {
            x: 512_000.0 + 0.25 * u + 0.001 * (i % 7) as f64,
            y: 5_403_000.0 + 0.25 * v,
            z: 0.02 * (u * u + v * v).sqrt() + 0.0025 * (i % 5) as f64,
            intensity: (i * 977 % 65536) as u16,
            return_number: (i % nret as usize) as u8 + 1,
            number_of_returns: nret,
            scan_direction: if i % 2 == 0 {
                ScanDirection::LeftToRight
            } else {
                ScanDirection::RightToLeft
            },
            is_edge_of_flight_line: i % 11 == 0,
            classification: Classification::new(class).unwrap_or(Classification::Ground),
            is_synthetic: i % 13 == 0,
            is_key_point: i % 17 == 0,
            is_withheld: i % 19 == 0,
            is_overlap: extended && i % 23 == 0,
            scanner_channel: if extended { (i % 4) as u8 } else { 0 },
            scan_angle: if extended {
                (i as f32 * 0.006) - 3.0
            } else {
                (i % 181) as f32 - 90.0
            },
            user_data: (i * 31 % 256) as u8,
            point_source_id: (i * 101 % 65536) as u16,
            gps_time: f.has_gps_time.then_some(3.0e8 + i as f64 * 1.0e-5),
            color: f.has_color.then(|| {
                let c = |k: usize| {
                    if wide {
                        (i * k * 257 % 65536) as u16
                    } else {
                        (i * k % 256) as u16
                    }
                };
                Color::new(c(3), c(5), c(7))
            }),
            waveform: f.has_waveform.then_some(Waveform {
                wave_packet_descriptor_index: 1,
                byte_offset_to_waveform_data: 60 + i as u64 * 64,
                waveform_packet_size_in_bytes: 64,
                return_point_waveform_location: i as f32 * 0.5,
                x_t: 0.1,
                y_t: -0.2,
                z_t: 0.97,
            }),
            nir: f.has_nir.then_some((i * 13 % 65536) as u16),
            extra_bytes: vec![i as u8, (i >> 8) as u8, 0xA5],
        };
        w.write_point(p).unwrap();
    }
    w.close().unwrap();
}

/// Every (version, point format) pair LAS defines.
fn matrix() -> Vec<((u8, u8), u8)> {
    let mut m = Vec::new();
    m.extend((0..=3).map(|f| ((1, 2), f)));
    m.extend((0..=5).map(|f| ((1, 3), f)));
    m.extend((0..=10).map(|f| ((1, 4), f)));
    m
}

fn vlr_key(v: &Vlr) -> (String, u16) {
    (v.user_id.clone(), v.record_id)
}

/// Checks `output` against `input`: header fields, VLRs and EVLRs, every
/// point's fields and extra bytes; with `normals`, the appended NormalX/Y/Z
/// are unit vectors and described after the input's own extra bytes.
fn assert_kept(input: &Path, output: &Path, normals: bool, what: &str) {
    let mut a = Reader::from_path(input).unwrap();
    let mut b = Reader::from_path(output).unwrap();
    let (ha, hb) = (a.header().clone(), b.header().clone());
    assert_eq!(ha.version(), hb.version(), "{what}: version");
    let (fa, fb) = (ha.point_format(), hb.point_format());
    assert_eq!(
        fa.to_u8().unwrap(),
        fb.to_u8().unwrap(),
        "{what}: point format"
    );
    assert_eq!(ha.transforms(), hb.transforms(), "{what}: scale and offset");
    assert_eq!(
        ha.number_of_points(),
        hb.number_of_points(),
        "{what}: count"
    );
    // Points by return as the headers hold them: LAS 1.4's 15 counts (the
    // legacy 5 of formats 6-10 are zero in scanmesh's output, as LAS 1.4
    // R15 sec. 2.4 asks, whatever the input wrote there), else the 5.
    let raw = |p: &Path| las::raw::Header::read_from(std::fs::File::open(p).unwrap()).unwrap();
    let (ra, rb) = (raw(input), raw(output));
    match (ra.large_file, rb.large_file) {
        (Some(la), Some(lb)) => assert_eq!(
            la.number_of_points_by_return, lb.number_of_points_by_return,
            "{what}: points by return"
        ),
        _ => assert_eq!(
            ra.number_of_points_by_return, rb.number_of_points_by_return,
            "{what}: points by return"
        ),
    }
    if fa.is_extended {
        assert_eq!(
            rb.number_of_points_by_return, [0; 5],
            "{what}: legacy counts"
        );
    }
    assert_eq!(ha.system_identifier(), hb.system_identifier(), "{what}");
    assert_eq!(ha.has_wkt_crs(), hb.has_wkt_crs(), "{what}: WKT bit");
    // Bounds: within a quantum of the input's (some writers bound the
    // points before quantising them); exact ones are checked below.
    let (ba, bb) = (ha.bounds(), hb.bounds());
    let t = ha.transforms();
    for (a, b, q) in [
        (ba.min.x, bb.min.x, t.x.scale),
        (ba.min.y, bb.min.y, t.y.scale),
        (ba.min.z, bb.min.z, t.z.scale),
        (ba.max.x, bb.max.x, t.x.scale),
        (ba.max.y, bb.max.y, t.y.scale),
        (ba.max.z, bb.max.z, t.z.scale),
    ] {
        assert!((a - b).abs() <= q, "{what}: bounds {ba:?} -> {bb:?}");
    }
    // VLRs: the input's, in its order (CRS first); only the Extra Bytes
    // VLR may grow, and only by descriptors appended after its own.
    // LASzip's VLR describes the compression: the output's own.
    let kept = |h: &las::Header| -> Vec<Vlr> {
        let v = h.vlrs().iter().filter(|v| v.user_id != "laszip encoded");
        v.cloned().collect()
    };
    let (va, vb) = (kept(&ha), kept(&hb));
    let keys = |v: &[Vlr]| v.iter().map(vlr_key).collect::<Vec<_>>();
    let (ka, kb) = (keys(&va), keys(&vb));
    let described = va.iter().any(|v| vlr_key(v) == ("LASF_Spec".into(), 4));
    let added = usize::from(normals && !described);
    assert_eq!(kb.len(), ka.len() + added, "{what}: VLRs {kb:?}");
    assert_eq!(kb[..ka.len()], ka[..], "{what}: VLRs");
    for (va, vb) in va.iter().zip(&vb) {
        assert_eq!(va.description, vb.description, "{what}: VLR description");
        if va.user_id == "LASF_Spec" && va.record_id == 4 && normals {
            assert_eq!(
                vb.data[..va.data.len()],
                va.data[..],
                "{what}: extra bytes VLR"
            );
            assert_eq!(
                vb.data.len(),
                va.data.len() + 4 * 192,
                "{what}: 4 new fields"
            );
        } else {
            assert_eq!(
                va.data, vb.data,
                "{what}: VLR {} {}",
                va.user_id, va.record_id
            );
        }
    }
    let ea: Vec<_> = ha.evlrs().to_vec();
    assert_eq!(ea, hb.evlrs().to_vec(), "{what}: EVLRs byte for byte");
    assert_eq!(
        usize::from(fb.extra_bytes),
        usize::from(fa.extra_bytes) + if normals { 13 } else { 0 },
        "{what}: extra bytes"
    );
    let (da, db) = (a.read_all().unwrap(), b.read_all().unwrap());
    assert_eq!(da.len(), db.len(), "{what}: points read");
    let ints = |d: &las::PointData| -> Vec<[i32; 3]> {
        d.x_raw()
            .zip(d.y_raw())
            .zip(d.z_raw())
            .map(|((x, y), z)| [x, y, z])
            .collect()
    };
    assert_eq!(ints(&da), ints(&db), "{what}: integer coordinates");
    // The output's bounds are its points' (scale x integer + offset).
    let lo = |v: Vec<f64>| v.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = |v: Vec<f64>| v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let exact = [
        lo(db.x().collect()),
        lo(db.y().collect()),
        lo(db.z().collect()),
        hi(db.x().collect()),
        hi(db.y().collect()),
        hi(db.z().collect()),
    ];
    let stated = [bb.min.x, bb.min.y, bb.min.z, bb.max.x, bb.max.y, bb.max.z];
    assert_eq!(stated, exact, "{what}: bounds of the points");
    let pa: Vec<Point> = da.points().map(|p| p.unwrap()).collect();
    let pb: Vec<Point> = db.points().map(|p| p.unwrap()).collect();
    for (i, (p, q)) in pa.iter().zip(&pb).enumerate() {
        let mut q2 = q.clone();
        q2.extra_bytes.truncate(p.extra_bytes.len());
        assert_eq!(*p, q2, "{what}: point {i}");
        if normals {
            let e = &q.extra_bytes[p.extra_bytes.len()..];
            let f = |k: usize| f32::from_le_bytes(e[4 * k..4 * k + 4].try_into().unwrap());
            let len = (f(0) * f(0) + f(1) * f(1) + f(2) * f(2)).sqrt();
            assert!(
                (len - 1.0).abs() < 1e-5,
                "{what}: point {i} normal length {len}"
            );
        }
    }
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn convert_and_normals_keep_every_field_of_every_version_and_format() {
    let dir = tempfile::tempdir().unwrap();
    for (version, format) in matrix() {
        let name = format!("v1{}_f{format}", version.1);
        let input = dir.path().join(format!("{name}.las"));
        synthetic(&input, version, format, 400);
        for ext in ["las", "laz"] {
            let conv = dir.path().join(format!("{name}_c.{ext}"));
            scanmesh(&["convert", s(&input), s(&conv)]);
            assert_kept(&input, &conv, false, &format!("convert {name} -> {ext}"));
            let norm = dir.path().join(format!("{name}_n.{ext}"));
            scanmesh(&["normals", s(&input), "-o", s(&norm)]);
            assert_kept(&input, &norm, true, &format!("normals {name} -> {ext}"));
        }
    }
}

/// The real fixtures, through both commands.
#[test]
fn real_files_keep_every_field() {
    let dir = tempfile::tempdir().unwrap();
    for name in fixtures() {
        let input = fixture(name);
        for ext in ["las", "laz"] {
            let conv = dir.path().join(format!("{name}_c.{ext}"));
            scanmesh(&["convert", s(&input), s(&conv)]);
            assert_kept(&input, &conv, false, &format!("convert {name} -> {ext}"));
            let norm = dir.path().join(format!("{name}_n.{ext}"));
            scanmesh(&["normals", s(&input), "-o", s(&norm)]);
            assert_kept(&input, &norm, true, &format!("normals {name} -> {ext}"));
        }
    }
}

fn fixtures() -> Vec<&'static str> {
    vec![
        "autzen.las",
        "32-1-472-150-76.laz",
        "pdal-test1_4.las",
        "autzen-trim-7-crop.las",
        "warsaw_small.las",
        "extrabytes.las",
    ]
}

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/las")
        .join(name)
}

/// Red, green, blue of every vertex of a binary little-endian PLY whose
/// vertex properties are scalars (the test's own parser).
fn ply_rgb(path: &Path) -> Vec<[u8; 3]> {
    let bytes = std::fs::read(path).unwrap();
    let end = b"end_header\n";
    let at = bytes.windows(end.len()).position(|w| w == end).unwrap() + end.len();
    let header = String::from_utf8_lossy(&bytes[..at]).into_owned();
    let mut n = 0;
    let (mut props, mut stride) = (Vec::new(), 0);
    for line in header.lines() {
        let w: Vec<&str> = line.split_whitespace().collect();
        match w.as_slice() {
            ["element", "vertex", count] => n = count.parse().unwrap(),
            ["property", t, name] => {
                let size = match *t {
                    "char" | "uchar" => 1,
                    "short" | "ushort" => 2,
                    "int" | "uint" | "float" => 4,
                    _ => 8,
                };
                props.push((name.to_string(), *t == "uchar", stride));
                stride += size;
            }
            _ => {}
        }
    }
    let at_of = |c: &str| {
        let p = props.iter().find(|p| p.0 == c).unwrap();
        assert!(p.1, "{c} is not uchar");
        p.2
    };
    let rgb = [at_of("red"), at_of("green"), at_of("blue")];
    (0..n)
        .map(|i| rgb.map(|o| bytes[at + i * stride + o]))
        .collect()
}

/// Colour of every point of a LAS file, read by the `las` crate.
fn las_rgb(path: &Path) -> Vec<(u16, u16, u16)> {
    let data = Reader::from_path(path).unwrap().read_all().unwrap();
    data.rgb().unwrap().collect()
}

/// 8-bit colour in LAS's 16-bit fields (every channel <= 255, as in PDAL's
/// autzen) reaches 8-bit PLY as it is, not black; true 16-bit colour
/// reaches it by its high byte; a LAS output keeps either, 16 bits wide.
#[test]
fn eight_and_sixteen_bit_colour_reach_ply_and_las() {
    let dir = tempfile::tempdir().unwrap();
    for (name, eight) in [
        ("autzen-trim-7-crop.las", true),
        ("warsaw_small.las", false),
    ] {
        let input = fixture(name);
        let want = las_rgb(&input);
        assert_eq!(
            want.iter().all(|c| c.0 <= 255 && c.1 <= 255 && c.2 <= 255),
            eight,
            "{name}: the fixture's colour depth"
        );
        assert!(want.iter().any(|c| c.0 > 0), "{name}: not all black");
        let expect: Vec<[u8; 3]> = want
            .iter()
            .map(|&(r, g, b)| match eight {
                true => [r as u8, g as u8, b as u8],
                false => [(r >> 8) as u8, (g >> 8) as u8, (b >> 8) as u8],
            })
            .collect();
        let conv = dir.path().join(format!("{name}_c.ply"));
        scanmesh(&["convert", s(&input), s(&conv)]);
        assert_eq!(ply_rgb(&conv), expect, "{name}: convert to PLY");
        let norm = dir.path().join(format!("{name}_n.ply"));
        scanmesh(&["normals", s(&input), "-o", s(&norm)]);
        assert_eq!(ply_rgb(&norm), expect, "{name}: normals to PLY");
        for (cmd, out) in [("convert", "c.laz"), ("normals", "n.las")] {
            let out = dir.path().join(format!("{name}_{out}"));
            match cmd {
                "convert" => scanmesh(&["convert", s(&input), s(&out)]),
                _ => scanmesh(&["normals", s(&input), "-o", s(&out)]),
            };
            assert_eq!(las_rgb(&out), want, "{name}: {cmd} to LAS");
        }
    }
}

/// A COPC file is read as the LAZ it is; `info` says it is a COPC; a LAS
/// output keeps its points and CRS but not the COPC records (their byte
/// offsets index the input's octree chunks, which the output does not have).
#[test]
fn copc_is_named_by_info_and_read_as_laz() {
    let input = fixture("1.2-with-color.copc.laz");
    let out = scanmesh(&["info", s(&input), "--json"]);
    let info: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(info["las"]["copc"], true, "{info}");
    assert_eq!(info["las"]["version"], "1.4", "{info}");
    assert_eq!(info["las"]["point_format"], 7, "{info}");
    assert_eq!(info["points"], 1065, "{info}");
    let text = scanmesh(&["info", s(&input)]);
    assert!(String::from_utf8_lossy(&text.stdout).contains("copc: yes"));
    let plain = scanmesh(&["info", s(&fixture("autzen.las")), "--json"]);
    let plain: serde_json::Value = serde_json::from_slice(&plain.stdout).unwrap();
    assert_eq!(plain["las"]["copc"], false, "{plain}");

    let dir = tempfile::tempdir().unwrap();
    let conv = dir.path().join("c.laz");
    scanmesh(&["convert", s(&input), s(&conv)]);
    let (mut a, mut b) = (
        Reader::from_path(&input).unwrap(),
        Reader::from_path(&conv).unwrap(),
    );
    let ids = |h: &las::Header| -> Vec<(String, u16)> {
        h.all_vlrs()
            .filter(|v| v.user_id != "laszip encoded")
            .map(vlr_key)
            .collect()
    };
    assert_eq!(
        ids(b.header()),
        [("LASF_Projection".to_string(), 2112)],
        "only the CRS kept"
    );
    let wkt = |h: &las::Header| h.vlrs().iter().find(|v| v.record_id == 2112).cloned();
    assert_eq!(wkt(a.header()), wkt(b.header()));
    assert_eq!(a.header().transforms(), b.header().transforms());
    let (da, db) = (a.read_all().unwrap(), b.read_all().unwrap());
    assert_eq!(da.raw_bytes(), db.raw_bytes(), "records byte for byte");
}

/// A VLR or EVLR that runs past its place is an error naming the file and
/// the record, from every command that reads the file; no output is left.
#[test]
fn a_record_running_past_its_place_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let good = dir.path().join("good.las");
    synthetic(&good, (1, 4), 6, 100);
    let bytes = std::fs::read(&good).unwrap();
    let u16_at = |at: usize| usize::from(u16::from_le_bytes([bytes[at], bytes[at + 1]]));
    let u64_at = |at: usize| u64::from_le_bytes(bytes[at..at + 8].try_into().unwrap()) as usize;
    // LAS 1.4 R15 table 3: header size at 94, first EVLR at 235, their
    // count at 243; a VLR's length at 20 into it, an EVLR's at 20 (u64).
    let header_size = u16_at(94);
    let first_evlr = u64_at(235);
    let cases: [(&str, usize, Vec<u8>, &str); 3] = [
        (
            "vlr",
            header_size + 20,
            60000u16.to_le_bytes().to_vec(),
            "VLR 0 of 2 runs past the start of the points",
        ),
        (
            "evlr_count",
            243,
            2u32.to_le_bytes().to_vec(),
            "EVLR 1 of 2 (its header) runs past the end of the file",
        ),
        (
            "evlr_len",
            first_evlr + 20,
            1_000_000_000u64.to_le_bytes().to_vec(),
            "EVLR 0 of 1 (1000000000 bytes of data) runs past the end of the file",
        ),
    ];
    for (name, at, patch, says) in cases {
        let mut bad = bytes.clone();
        bad[at..at + patch.len()].copy_from_slice(&patch);
        let input = dir.path().join(format!("{name}.las"));
        std::fs::write(&input, bad).unwrap();
        let outs = [
            dir.path().join(format!("{name}_c.las")),
            dir.path().join(format!("{name}_n.ply")),
        ];
        let runs: [Vec<&str>; 3] = [
            vec!["convert", s(&input), s(&outs[0])],
            vec!["normals", s(&input), "-o", s(&outs[1])],
            vec!["info", s(&input)],
        ];
        for args in runs {
            let out = Command::new(env!("CARGO_BIN_EXE_scanmesh"))
                .args(&args)
                .output()
                .unwrap();
            let err = String::from_utf8_lossy(&out.stderr);
            assert!(!out.status.success(), "{name}: {args:?} succeeded");
            assert!(
                err.contains(s(&input)) && err.contains(says),
                "{name}: {args:?}: {err}"
            );
            assert!(!err.contains("panicked"), "{err}");
        }
        for o in &outs {
            assert!(!o.exists(), "{name}: {} left behind", o.display());
        }
    }
}

/// A LAS 1.3 file's waveform data packets (one record of the EVLR layout
/// after the points, LAS 1.3 R11 sec. 2.2) come after the output's points
/// byte for byte, and the header points at them.
#[test]
fn las_1_3_waveform_packets_are_copied_after_the_points() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("w.las");
    synthetic(&input, (1, 3), 4, 400);
    // Append the packets: a 60-byte EVLR-layout header, then the data.
    let mut bytes = std::fs::read(&input).unwrap();
    let at = bytes.len() as u64;
    let data: Vec<u8> = (0..5000u32).map(|i| (i * 13 % 251) as u8).collect();
    bytes.extend(0u16.to_le_bytes());
    let mut user = [0u8; 16];
    user[..9].copy_from_slice(b"LASF_Spec");
    bytes.extend(user);
    bytes.extend(65535u16.to_le_bytes());
    bytes.extend((data.len() as u64).to_le_bytes());
    bytes.extend([0u8; 32]);
    bytes.extend(&data);
    // Start of waveform data packet record (u64 at 227); global encoding
    // bit 1: the packets are in this file.
    bytes[227..235].copy_from_slice(&at.to_le_bytes());
    bytes[6] |= 2;
    std::fs::write(&input, &bytes).unwrap();
    for (cmd, name) in [("convert", "c.las"), ("normals", "n.laz")] {
        let out = dir.path().join(name);
        match cmd {
            "convert" => scanmesh(&["convert", s(&input), s(&out)]),
            _ => scanmesh(&["normals", s(&input), "-o", s(&out)]),
        };
        let got = std::fs::read(&out).unwrap();
        let raw = las::raw::Header::read_from(&got[..]).unwrap();
        let start = raw.start_of_waveform_data_packet_record.unwrap() as usize;
        assert!(start > 0, "{cmd}: no waveform start");
        assert_eq!(
            got[start..],
            bytes[at as usize..],
            "{cmd}: packets byte for byte"
        );
        assert_eq!(got[6] & 2, 2, "{cmd}: global encoding");
        assert_kept(&input, &out, cmd == "normals", cmd);
    }
}
