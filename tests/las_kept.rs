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
    assert_eq!(ha.bounds(), hb.bounds(), "{what}: bounds");
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
    vec!["autzen.las", "32-1-472-150-76.laz"]
}

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/las")
        .join(name)
}
