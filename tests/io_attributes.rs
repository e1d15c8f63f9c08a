//! Point attributes (intensity, colour, classification, return number, GPS
//! time) through every format that holds them, through `convert` between
//! every pair, and through a store: `normals` writes them beside the
//! normals, in input order, whatever the tiling.

use glam::DVec3;
use scanmesh::io::convert::convert;
use scanmesh::io::{
    create_writer, create_writer_with, open_reader, Attribute, AttributeSet, AttributeValues,
    Attributes, Format, InvalidPolicy, LasOutput, PointChunk, WriterSpec,
};
use scanmesh::pipeline::NoProgress;
use scanmesh::synth::Rng;
use std::path::Path;
use std::process::Command;

/// A scattered cloud with every attribute; colours are 8-bit values widened
/// (x257) when `eight_bit`, so that every format holds them exactly.
fn cloud(n: usize, seed: u64, eight_bit: bool) -> PointChunk {
    let mut r = Rng::new(seed);
    let mut chunk = PointChunk::default();
    chunk.attrs.reset(AttributeSet::all());
    for i in 0..n {
        chunk.xyz.push(DVec3::new(
            r.range(0.0, 10.0),
            r.range(0.0, 10.0),
            r.range(0.0, 1.0),
        ));
        let channel = |r: &mut Rng| match eight_bit {
            true => (r.next_u64() % 256) as u16 * 257,
            false => r.next_u64() as u16,
        };
        chunk.attrs.push(&AttributeValues {
            intensity: r.next_u64() as u16,
            rgb: [channel(&mut r), channel(&mut r), channel(&mut r)],
            classification: (r.next_u64() % 32) as u8,
            return_number: (r.next_u64() % 6) as u8,
            gps_time: 3.0e8 + i as f64 * 1.25e-5 + r.range(0.0, 1e-6),
        });
    }
    chunk
}

fn write(path: &Path, chunk: &PointChunk, format: Format, set: AttributeSet) {
    let mut b = scanmesh::geom::Aabb::EMPTY;
    chunk.xyz.iter().for_each(|p| b.add(*p));
    let spec = WriterSpec {
        attributes: set,
        bounds: Some(b),
        ..WriterSpec::new(format)
    };
    let mut w = create_writer(path, &spec).unwrap();
    w.write_chunk(chunk, None).unwrap();
    w.finish().unwrap();
}

/// Every point and attribute of a file, in file order.
fn read(path: &Path) -> (Vec<DVec3>, Attributes) {
    let mut r = open_reader(path, InvalidPolicy::Reject).unwrap();
    let set = r.info().attributes;
    let mut xyz = Vec::new();
    let mut all = Attributes::default();
    all.reset(set);
    let mut chunk = PointChunk::default();
    // Small chunks: values must stay with their points across chunk ends.
    while r.read_chunk(&mut chunk, 777).unwrap() > 0 {
        assert_eq!(chunk.attrs.set(), set);
        xyz.extend_from_slice(&chunk.xyz);
        (0..chunk.len()).for_each(|i| all.push(&chunk.attrs.get(i)));
    }
    (xyz, all)
}

fn assert_same_attributes(a: &Attributes, b: &Attributes, set: AttributeSet, what: &str) {
    assert_eq!(b.set().intersect(set), set, "{what}: attribute set");
    let n = a.len_of(Attribute::Intensity).max(a.len_of(Attribute::Rgb));
    for i in 0..n {
        let (x, y) = (a.get(i), b.get(i));
        for attr in set.iter() {
            let same = match attr {
                Attribute::Intensity => x.intensity == y.intensity,
                Attribute::Rgb => x.rgb == y.rgb,
                Attribute::Classification => x.classification == y.classification,
                Attribute::ReturnNumber => x.return_number == y.return_number,
                Attribute::GpsTime => x.gps_time == y.gps_time,
            };
            assert!(same, "{what}: point {i} {attr:?}: {x:?} vs {y:?}");
        }
    }
}

const FORMATS: [(&str, Format); 5] = [
    ("ply", Format::PlyBinaryLe),
    ("ascii.ply", Format::PlyAscii),
    ("las", Format::Las),
    ("laz", Format::Laz),
    ("pcd", Format::Pcd),
];

#[test]
fn every_format_pair_carries_every_attribute() {
    let dir = tempfile::tempdir().unwrap();
    let src = cloud(3000, 7, true);
    let all = AttributeSet::all();
    for (from_ext, from_format) in FORMATS {
        let from = dir.path().join(format!("src.{from_ext}"));
        write(&from, &src, from_format, all);
        let (xyz, attrs) = read(&from);
        assert_eq!(xyz.len(), src.len());
        assert_same_attributes(&src.attrs, &attrs, all, from_ext);
        for (to_ext, _) in FORMATS {
            let to = dir.path().join(format!("{from_ext}-to.{to_ext}"));
            let stats = convert(&from, &to, InvalidPolicy::Reject, &NoProgress).unwrap();
            assert_eq!((stats.carried, stats.dropped), (all, AttributeSet::EMPTY));
            let (_, back) = read(&to);
            assert_same_attributes(&src.attrs, &back, all, &format!("{from_ext} -> {to_ext}"));
        }
    }
}

#[test]
fn sixteen_bit_colour_is_exact_in_las_and_keeps_its_high_byte_in_ply_and_pcd() {
    let dir = tempfile::tempdir().unwrap();
    let src = cloud(500, 9, false);
    let las = dir.path().join("c.las");
    write(&las, &src, Format::Las, AttributeSet::all());
    assert_same_attributes(&src.attrs, &read(&las).1, AttributeSet::all(), "las");
    for ext in ["ply", "pcd"] {
        let out = dir.path().join(format!("c.{ext}"));
        convert(&las, &out, InvalidPolicy::Reject, &NoProgress).unwrap();
        let (_, back) = read(&out);
        for (i, (a, b)) in src.attrs.rgb.iter().zip(&back.rgb).enumerate() {
            assert_eq!(a.map(|v| v >> 8), b.map(|v| v >> 8), "{ext} point {i}");
            assert_eq!(b.map(|v| v % 257), [0; 3], "{ext}: widened 8-bit values");
        }
    }
}

#[test]
fn formats_without_attributes_drop_them_and_say_so() {
    let dir = tempfile::tempdir().unwrap();
    let las = dir.path().join("a.las");
    write(&las, &cloud(100, 3, true), Format::Las, AttributeSet::all());
    let xyz = dir.path().join("a.xyz");
    let stats = convert(&las, &xyz, InvalidPolicy::Reject, &NoProgress).unwrap();
    assert_eq!(
        (stats.carried, stats.dropped),
        (AttributeSet::EMPTY, AttributeSet::all())
    );
    let out = Command::new(env!("CARGO_BIN_EXE_scanmesh"))
        .args(["convert", las.to_str().unwrap(), xyz.to_str().unwrap()])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains("cannot hold the input's intensity, rgb, classification"),
        "{err}"
    );
    // Asking a writer for what its format cannot hold is an error.
    let spec = WriterSpec {
        attributes: AttributeSet::of(&[Attribute::Rgb]),
        ..WriterSpec::new(Format::Xyz)
    };
    let e = create_writer(&dir.path().join("b.xyz"), &spec)
        .err()
        .unwrap();
    assert!(e.to_string().contains("cannot hold rgb"), "{e}");
}

#[test]
fn las_classes_beyond_formats_0_to_3_are_an_error_not_truncated() {
    let dir = tempfile::tempdir().unwrap();
    let mut src = cloud(10, 1, true);
    src.attrs.classification[4] = 40;
    src.attrs.return_number[6] = 12;
    let spec = WriterSpec {
        attributes: AttributeSet::all(),
        las_transform: Some(scanmesh::io::LasTransform {
            scale: DVec3::splat(1e-3),
            offset: DVec3::ZERO,
        }),
        ..WriterSpec::new(Format::Las)
    };
    // Format 3 asked for: class 40 does not fit its 5 bits.
    let asked = LasOutput {
        point_format: Some(3),
        ..LasOutput::default()
    };
    let mut w = create_writer_with(&dir.path().join("x.las"), &spec, &asked).unwrap();
    let e = w.write_chunk(&src, None).unwrap_err().to_string();
    assert!(
        e.contains("point 4 has class 40; LAS point format 3 holds up to 31: point format 7 (LAS 1.4) holds it"),
        "{e}"
    );
    // Unasked, the values are unknown before the first point: LAS 1.4
    // format 7 (GPS time and colour), which holds both.
    let out = dir.path().join("y.las");
    let mut w = create_writer(&out, &spec).unwrap();
    w.write_chunk(&src, None).unwrap();
    w.finish().unwrap();
    let back = read(&out).1;
    assert_eq!(back.classification, src.attrs.classification);
    assert_eq!(back.return_number, src.attrs.return_number);
    let header = las::Reader::from_path(&out).unwrap().header().clone();
    assert_eq!(
        (
            header.version().minor,
            header.point_format().to_u8().unwrap()
        ),
        (4, 7)
    );
}

#[test]
fn other_writers_names_are_read() {
    let dir = tempfile::tempdir().unwrap();
    // CloudCompare's scalar fields (float intensity) and uchar colour.
    let ply = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n\
               property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n\
               property float scalar_Intensity\nproperty float scalar_Classification\n\
               property double scalar_GpsTime\nend_header\n\
               0 0 0 255 0 10 812.4 2 1000.5\n1 0 0 1 2 3 70000 6 1001.25\n";
    let p = dir.path().join("cc.ply");
    std::fs::write(&p, ply).unwrap();
    let (_, a) = read(&p);
    let expect = AttributeSet::of(&[
        Attribute::Intensity,
        Attribute::Rgb,
        Attribute::Classification,
        Attribute::GpsTime,
    ]);
    assert_eq!(a.set(), expect);
    assert_eq!(a.rgb, [[65535, 0, 2570], [257, 514, 771]]);
    assert_eq!(a.intensity, [812, 65535]);
    assert_eq!(a.classification, [2, 6]);
    assert_eq!(a.gps_time, [1000.5, 1001.25]);
    // PCL's ASCII PCD prints a packed colour as the integer of its bits.
    let pcd = "VERSION 0.7\nFIELDS x y z rgb intensity\nSIZE 4 4 4 4 4\nTYPE F F F F F\n\
               COUNT 1 1 1 1 1\nWIDTH 1\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 1\n\
               DATA ascii\n1 2 3 16711935 7\n";
    let p = dir.path().join("pcl.pcd");
    std::fs::write(&p, pcd).unwrap();
    let (_, a) = read(&p);
    assert_eq!(
        a.set(),
        AttributeSet::of(&[Attribute::Intensity, Attribute::Rgb])
    );
    assert_eq!((a.rgb[0], a.intensity[0]), ([65535, 0, 65535], 7));
}

fn scanmesh(args: &[&str]) {
    let out = Command::new(env!("CARGO_BIN_EXE_scanmesh"))
        .args(args)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{args:?}: {err}");
}

/// Points on a wavy sheet (so normals are well defined), in a shuffled
/// scan order so input order and tile order differ.
fn sheet(n: usize) -> PointChunk {
    let mut c = cloud(n, 11, true);
    let mut r = Rng::new(5);
    for p in &mut c.xyz {
        let (x, y) = (r.range(0.0, 10.0), r.range(0.0, 10.0));
        *p = DVec3::new(x, y, 0.3 * (x * 0.7).sin() * (y * 0.5).cos());
    }
    c
}

#[test]
fn normals_write_the_inputs_attributes_in_input_order_for_any_tiling() {
    let dir = tempfile::tempdir().unwrap();
    let src = sheet(6000);
    let las = dir.path().join("scan.las");
    write(&las, &src, Format::Las, AttributeSet::all());
    let (in_xyz, in_attrs) = read(&las);
    let mut outputs = Vec::new();
    for tile_points in ["100000", "300"] {
        let out = dir.path().join(format!("n{tile_points}.ply"));
        scanmesh(&[
            "normals",
            las.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--tile-points",
            tile_points,
            "-q",
        ]);
        let (xyz, attrs) = read(&out);
        assert_eq!(xyz.len(), in_xyz.len());
        assert_same_attributes(&in_attrs, &attrs, AttributeSet::all(), tile_points);
        // Positions come back through the store's f32 coordinates.
        for (a, b) in xyz.iter().zip(&in_xyz) {
            assert!(a.distance(*b) < 1e-5, "{a} vs {b}");
        }
        outputs.push(std::fs::read(&out).unwrap());
    }
    assert!(outputs[0] == outputs[1], "tiling changed the output");
    // Through a store made first: the store keeps them.
    let store = dir.path().join("scan.store");
    scanmesh(&[
        "tile",
        las.to_str().unwrap(),
        "-o",
        store.to_str().unwrap(),
        "-q",
    ]);
    let pcd = dir.path().join("n.pcd");
    scanmesh(&[
        "normals",
        store.to_str().unwrap(),
        "-o",
        pcd.to_str().unwrap(),
        "-q",
    ]);
    assert_same_attributes(
        &in_attrs,
        &read(&pcd).1,
        AttributeSet::all(),
        "store -> pcd",
    );
}

#[test]
fn e57_carries_intensity_and_colour() {
    let dir = tempfile::tempdir().unwrap();
    let src = cloud(2000, 4, false);
    let las = dir.path().join("s.las");
    write(&las, &src, Format::Las, AttributeSet::all());
    let held = AttributeSet::of(&[Attribute::Intensity, Attribute::Rgb]);
    let e57 = dir.path().join("s.e57");
    let stats = convert(&las, &e57, InvalidPolicy::Reject, &NoProgress).unwrap();
    assert_eq!(
        (stats.carried, stats.dropped),
        (held, AttributeSet::all().without(held))
    );
    let (xyz, back) = read(&e57);
    assert_eq!((xyz.len(), back.set()), (src.len(), held));
    assert_same_attributes(&src.attrs, &back, held, "las -> e57");
    let las2 = dir.path().join("t.las");
    convert(&e57, &las2, InvalidPolicy::Reject, &NoProgress).unwrap();
    assert_same_attributes(&src.attrs, &read(&las2).1, held, "e57 -> las");
}

/// Normals of a file, in file order.
fn normals_of(path: &Path) -> Vec<glam::Vec3> {
    let mut r = open_reader(path, InvalidPolicy::Reject).unwrap();
    let mut out = Vec::new();
    let mut chunk = PointChunk::default();
    while r.read_chunk(&mut chunk, 1000).unwrap() > 0 {
        out.extend(chunk.normals.as_ref().expect("normals"));
    }
    out
}

#[test]
fn a_las_keeps_its_attributes_after_gaining_normals_in_las() {
    let dir = tempfile::tempdir().unwrap();
    let las = dir.path().join("scan.las");
    write(&las, &sheet(4000), Format::Las, AttributeSet::all());
    let (in_xyz, in_attrs) = read(&las);
    let (ply, out) = (dir.path().join("n.ply"), dir.path().join("n.laz"));
    for o in [&ply, &out] {
        scanmesh(&[
            "normals",
            las.to_str().unwrap(),
            "-o",
            o.to_str().unwrap(),
            "-q",
        ]);
    }
    let (xyz, attrs) = read(&out);
    assert_same_attributes(&in_attrs, &attrs, AttributeSet::all(), "normals -> laz");
    // Positions pass through the store's f32 coordinates and a new LAS
    // quantisation chosen from the bounds.
    assert_eq!(xyz.len(), in_xyz.len());
    for (a, b) in xyz.iter().zip(&in_xyz) {
        assert!(a.distance(*b) < 1e-5, "{a} vs {b}");
    }
    let (a, b) = (normals_of(&ply), normals_of(&out));
    assert!(a == b, "LAS extra-byte normals differ from the PLY's");
    assert!(a.iter().all(|n| (n.length() - 1.0).abs() < 1e-5));
    // And they survive a conversion back to PLY.
    let back = dir.path().join("back.ply");
    convert(&out, &back, InvalidPolicy::Reject, &NoProgress).unwrap();
    assert!(normals_of(&back) == a);
}

/// A LAS output of another format's points is the smallest LAS point
/// format that holds their attributes and values, the same from `convert`
/// and from a store (`normals`), compressed or not: LAS 1.2 format 3 for
/// classes up to 31, LAS 1.4 format 7 once a class needs 8 bits; every
/// point and class written as it is.
#[test]
fn other_inputs_get_the_smallest_las_format_that_holds_their_values() {
    let dir = tempfile::tempdir().unwrap();
    for (class, want) in [(31u8, (2u8, 3u8)), (200, (4, 7))] {
        let mut src = sheet(2000);
        src.attrs.classification[7] = class;
        let ply = dir.path().join(format!("c{class}.ply"));
        write(&ply, &src, Format::PlyBinaryLe, AttributeSet::all());
        for (cmd, ext) in [
            ("convert", "las"),
            ("convert", "laz"),
            ("normals", "las"),
            ("normals", "laz"),
        ] {
            let out = dir.path().join(format!("c{class}_{cmd}.{ext}"));
            let mut args = vec![cmd, ply.to_str().unwrap()];
            if cmd == "normals" {
                args.push("-o");
            }
            args.push(out.to_str().unwrap());
            let o = Command::new(env!("CARGO_BIN_EXE_scanmesh"))
                .args(&args)
                .output()
                .unwrap();
            assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
            let header = las::Reader::from_path(&out).unwrap().header().clone();
            let got = (
                header.version().minor,
                header.point_format().to_u8().unwrap(),
            );
            assert_eq!(got, want, "{cmd} .{ext}, largest class {class}");
            assert_eq!(header.number_of_points(), 2000, "{cmd} .{ext}");
            let (xyz, attrs) = read(&out);
            assert_eq!(xyz.len(), 2000, "{cmd} .{ext}");
            assert_eq!(
                attrs.classification, src.attrs.classification,
                "{cmd} .{ext}"
            );
        }
    }
}
