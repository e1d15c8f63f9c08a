//! The table from an output's file name to its writer: which format a name
//! asks for and whether that format holds what a command writes per point
//! (normals, computed values, flags), and which mesh format a mesh's or a
//! polyline's name asks for. Every command that writes points asks here
//! ([`output_spec`]), every one that writes a mesh or lines too
//! ([`mesh_format`]), so a new per-point output or a new format touches
//! this table and its writer, not the commands (PDAL's
//! `StageFactory::inferWriterDriver` is the model).

use super::{format_from_name, AttributeSet, Format, IoError, ValueField, WriterSpec};
use std::path::Path;

/// The mesh (and polyline) file formats.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeshFormat {
    /// Binary little-endian PLY.
    PlyBinary,
    /// ASCII PLY.
    PlyAscii,
    /// Wavefront OBJ (vertices and faces, or `l` lines).
    Obj,
}

/// The mesh formats by the extensions that ask for them.
const MESH_WRITERS: [(&str, MeshFormat); 2] =
    [("ply", MeshFormat::PlyBinary), ("obj", MeshFormat::Obj)];

/// The mesh format an output named `path` asks for (`ascii`: a PLY as
/// text); an unknown extension is an error naming the file and the ones
/// that would do.
pub fn mesh_format(path: &Path, ascii: bool) -> Result<MeshFormat, IoError> {
    let name = path
        .file_name()
        .and_then(|n| n.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    let ext = name.rsplit_once('.').map_or("", |(_, e)| e);
    match MESH_WRITERS.iter().find(|(e, _)| *e == ext) {
        Some((_, MeshFormat::PlyBinary)) if ascii => Ok(MeshFormat::PlyAscii),
        Some((_, format)) => Ok(*format),
        None => Err(IoError::Unsupported {
            path: path.to_path_buf(),
            reason: "unknown mesh format (use .ply or .obj)".into(),
        }),
    }
}

/// What a command writes per point beside the coordinates (and the
/// input's attributes, which the command sets on the spec it gets back).
#[derive(Clone, Copy, Debug, Default)]
pub struct Carried {
    /// Each point's normal: the format must hold it.
    pub normals: bool,
    /// Computed values, one named field each: the format must hold them.
    pub values: &'static [ValueField],
    /// A flags byte, written where the format holds one (not in XYZ text,
    /// whose columns carry no names, nor in E57).
    pub flags: bool,
    /// What the file holds, where the format has a comment.
    pub comment: Option<&'static str>,
}

impl Carried {
    /// Named values and a flags byte per point, and what the file holds:
    /// a per-point measure such as the curvature or the outlier score.
    pub fn values_and_flags(values: &'static [ValueField], comment: &'static str) -> Self {
        Carried {
            normals: false,
            values,
            flags: true,
            comment: Some(comment),
        }
    }
}

/// The formats an output may be written in, by the extensions that ask
/// for them, in the order an error lists them.
const WRITERS: [(&str, Format); 7] = [
    ("ply", Format::PlyBinaryLe),
    ("pcd", Format::Pcd),
    ("las", Format::Las),
    ("laz", Format::Laz),
    ("xyz", Format::Xyz),
    ("csv", Format::Xyz),
    ("e57", Format::E57),
];

impl Format {
    /// Whether this format holds a normal per point (PLY `nx ny nz`, PCD
    /// `normal_x..z`, LAS extra bytes `NormalX..Z`, XYZ's columns 4-6).
    pub fn holds_normals(self) -> bool {
        self != Format::E57
    }

    /// Whether this format holds a flags byte per point by name.
    pub fn holds_flags(self) -> bool {
        self.holds_values()
    }
}

/// The writer spec for an output named `path` carrying `carried`; with
/// `ascii`, a PLY output is written as text. An unknown extension, a
/// gzip name, or a format that cannot hold the normals or values asked
/// for is an error naming the file and the extensions that would do.
pub fn output_spec(path: &Path, carried: &Carried, ascii: bool) -> Result<WriterSpec, IoError> {
    let refuse = |reason: String| IoError::Unsupported {
        path: path.to_path_buf(),
        reason,
    };
    let holds = |f: Format| {
        (!carried.normals || f.holds_normals()) && (carried.values.is_empty() || f.holds_values())
    };
    let Some((mut format, gz)) = format_from_name(path) else {
        return Err(refuse(format!(
            "unknown output format (use {})",
            extensions(holds)
        )));
    };
    if gz {
        return Err(refuse(
            "gzip output is not supported; drop the .gz and compress the finished file".into(),
        ));
    }
    if !holds(format) {
        return Err(refuse(format!(
            "{} cannot hold {}; write {}",
            format,
            what(carried),
            extensions(holds)
        )));
    }
    if ascii && format == Format::PlyBinaryLe {
        format = Format::PlyAscii;
    }
    Ok(WriterSpec {
        with_normals: carried.normals,
        values: carried.values,
        with_flags: carried.flags && format.holds_flags(),
        comment: carried.comment,
        ..WriterSpec::new(format)
    })
}

impl WriterSpec {
    /// Carries those of the input's attributes this format holds; returns
    /// the others, which the output will not have ([`not_held`] says so).
    pub fn carry(&mut self, input: AttributeSet) -> AttributeSet {
        self.attributes = input.intersect(self.format.attributes());
        input.without(self.attributes)
    }
}

/// The note that `output` cannot hold the input's `dropped` attributes,
/// when there are any: a user who asked for a format learns what it lost.
pub fn not_held(output: &Path, dropped: AttributeSet) -> Option<String> {
    (!dropped.is_empty()).then(|| {
        format!(
            "{} cannot hold the input's {}: not written",
            output.display(),
            dropped.describe()
        )
    })
}

/// The extensions of the formats `holds` accepts: ".ply, .pcd or .las".
fn extensions(holds: impl Fn(Format) -> bool) -> String {
    let names: Vec<String> = WRITERS
        .iter()
        .filter(|(_, f)| holds(*f))
        .map(|(ext, _)| format!(".{ext}"))
        .collect();
    match names.split_last() {
        Some((last, rest)) if !rest.is_empty() => format!("{} or {last}", rest.join(", ")),
        Some((last, _)) => last.clone(),
        None => "nothing".into(),
    }
}

/// What is asked for, in words: "normals", "k1, k2".
fn what(carried: &Carried) -> String {
    let mut parts: Vec<&str> = Vec::new();
    if carried.normals {
        parts.push("normals");
    }
    parts.extend(carried.values.iter().map(|v| v.name));
    parts.join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;

    const K: &[ValueField] = &[ValueField {
        name: "k",
        description: "a value",
    }];

    fn spec(name: &str, carried: Carried) -> Result<WriterSpec, String> {
        output_spec(Path::new(name), &carried, false).map_err(|e| e.to_string())
    }

    #[test]
    fn every_point_format_is_found_by_its_extension() {
        let normals = Carried {
            normals: true,
            flags: true,
            ..Carried::default()
        };
        for (name, format, flags) in [
            ("a.ply", Format::PlyBinaryLe, true),
            ("a.PCD", Format::Pcd, true),
            ("a.las", Format::Las, true),
            ("a.laz", Format::Laz, true),
            ("a.xyz", Format::Xyz, false),
            ("a.csv", Format::Xyz, false),
        ] {
            let s = spec(name, normals).unwrap();
            assert_eq!(
                (s.format, s.with_normals, s.with_flags),
                (format, true, flags)
            );
        }
        let e = spec("a.e57", normals).unwrap_err();
        assert!(e.contains("E57 cannot hold normals"), "{e}");
        assert!(e.contains(".ply, .pcd, .las, .laz, .xyz or .csv"), "{e}");
    }

    #[test]
    fn values_need_named_fields() {
        let values = Carried {
            values: K,
            flags: true,
            ..Carried::default()
        };
        for name in ["a.ply", "a.pcd", "a.las", "a.laz"] {
            let s = spec(name, values).unwrap();
            assert_eq!((s.values, s.with_flags), (K, true), "{name}");
        }
        for name in ["a.xyz", "a.e57"] {
            let e = spec(name, values).unwrap_err();
            assert!(
                e.contains("cannot hold k; write .ply, .pcd, .las or .laz"),
                "{e}"
            );
        }
        let e = spec("a.obj", values).unwrap_err();
        assert!(e.contains("unknown output format (use .ply, .pcd, .las or .laz)"));
        let e = spec("a.ply.gz", values).unwrap_err();
        assert!(e.contains("gzip output is not supported"), "{e}");
    }

    #[test]
    fn meshes_are_ply_or_obj() {
        let f = |name: &str, ascii| mesh_format(Path::new(name), ascii).map_err(|e| e.to_string());
        assert_eq!(f("m.ply", false), Ok(MeshFormat::PlyBinary));
        assert_eq!(f("m.PLY", true), Ok(MeshFormat::PlyAscii));
        assert_eq!(f("m.obj", true), Ok(MeshFormat::Obj));
        for name in ["m.stl", "m", "m.ply.gz", ".ply.x"] {
            let e = f(name, false).unwrap_err();
            assert!(e.contains("unknown mesh format (use .ply or .obj)"), "{e}");
        }
    }

    #[test]
    fn ascii_asks_for_text_ply_only() {
        let s = output_spec(Path::new("a.ply"), &Carried::default(), true).unwrap();
        assert_eq!(s.format, Format::PlyAscii);
        let s = output_spec(Path::new("a.pcd"), &Carried::default(), true).unwrap();
        assert_eq!(s.format, Format::Pcd);
    }
}
