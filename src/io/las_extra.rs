//! LAS "extra bytes": the Extra Bytes VLR (`LASF_Spec`, record 4; ASPRS
//! LAS 1.4 R15 sec. 2.5.3.2) describes fields that follow the standard
//! point record, 192 bytes a field. scanmesh writes normals as three float
//! fields named `NormalX`, `NormalY`, `NormalZ` (PDAL's names for the same
//! dimensions) and its flags as one unsigned byte, `scanmesh_flags`, and
//! reads normals back from any file that describes them so. A LAS output
//! of a LAS input keeps the input's extra bytes and their descriptions and
//! appends its own after them ([`plan`]), or writes into the input's own
//! fields of those names (a file scanmesh wrote, processed again).

use super::las_file::{RecordHeader, Vlr, EXTRA_BYTES};
use super::{ValueField, WriterSpec};
use las::Header;

const DESCRIPTOR: usize = 192;
const NAME_AT: usize = 4;
const NAME_LEN: usize = 32;
const DESCRIPTION_AT: usize = 160;
/// Data type 1: u8; 9: f32.
const U8: u8 = 1;
const FLOAT: u8 = 9;
const NORMAL_NAMES: [&str; 3] = ["NormalX", "NormalY", "NormalZ"];
/// The name of scanmesh's flags byte.
const FLAGS_NAME: &str = "scanmesh_flags";

/// Bytes the normals take at the end of each record.
const NORMAL_BYTES: usize = 12;

/// Byte size of a described field: type 0 is `options` undocumented
/// bytes, 1-10 the scalar types, 11-30 LAS 1.4's deprecated arrays of two
/// or three of them.
fn field_size(data_type: u8, options: u8) -> Option<usize> {
    let scalar = |t: u8| match t {
        1 | 2 => Some(1),
        3 | 4 => Some(2),
        5 | 6 | 9 => Some(4),
        7 | 8 | 10 => Some(8),
        _ => None,
    };
    match data_type {
        0 => Some(usize::from(options)),
        1..=10 => scalar(data_type),
        11..=20 => scalar(data_type - 10).map(|s| 2 * s),
        21..=30 => scalar(data_type - 20).map(|s| 3 * s),
        _ => None,
    }
}

/// One described field: its name, type and offset within the extra bytes.
struct Field {
    name: String,
    description: String,
    data_type: u8,
    at: usize,
    size: usize,
}

/// The fields an Extra Bytes VLR's `data` describes, in order; `Err`
/// names the data type of a field whose size is unknown.
fn fields(data: &[u8]) -> Result<Vec<Field>, u8> {
    let mut at = 0;
    let mut out = Vec::new();
    for d in data.chunks_exact(DESCRIPTOR) {
        let size = field_size(d[2], d[3]).ok_or(d[2])?;
        let text = |raw: &[u8]| {
            let cut = raw.split(|&b| b == 0).next().unwrap_or(raw);
            String::from_utf8_lossy(cut).into_owned()
        };
        out.push(Field {
            name: text(&d[NAME_AT..NAME_AT + NAME_LEN]),
            description: text(&d[DESCRIPTION_AT..DESCRIPTION_AT + 32]),
            data_type: d[2],
            at,
            size,
        });
        at += size;
    }
    Ok(out)
}

/// Offset of the field named `name` of type `data_type` within `extra`
/// bytes.
fn find(fields: &[Field], name: &str, data_type: u8, extra: usize) -> Option<usize> {
    fields
        .iter()
        .find(|f| f.name.eq_ignore_ascii_case(name) && f.data_type == data_type)
        .filter(|f| f.at + f.size <= extra)
        .map(|f| f.at)
}

fn find_normal_fields(fields: &[Field], extra: usize) -> Option<[usize; 3]> {
    match NORMAL_NAMES.map(|n| find(fields, n, FLOAT, extra)) {
        [Some(x), Some(y), Some(z)] => Some([x, y, z]),
        _ => None,
    }
}

/// Offsets of `NormalX/Y/Z` within the extra bytes, when the header
/// describes all three as floats inside the record's extra bytes.
pub(crate) fn find_normals(header: &Header) -> Option<[usize; 3]> {
    let extra = usize::from(header.point_format().extra_bytes);
    let vlr = header
        .all_vlrs()
        .find(|v| v.user_id == EXTRA_BYTES.0 && v.record_id == EXTRA_BYTES.1)?;
    find_normal_fields(&fields(&vlr.data).ok()?, extra)
}

/// Where the input already holds `value`: a float field of its name that
/// scanmesh described (a file it wrote, processed again). A field of that
/// name the input made itself is its data: `Err`, never overwritten.
fn value_in_place(
    described: &[Field],
    value: &ValueField,
    extra: usize,
) -> Result<Option<usize>, String> {
    let Some(f) = described
        .iter()
        .find(|f| f.name.eq_ignore_ascii_case(value.name))
    else {
        return Ok(None);
    };
    let ours = f.data_type == FLOAT && f.description == value.description;
    match ours {
        true => Ok(find(described, value.name, FLOAT, extra)),
        false => Err(format!(
            "its extra bytes hold a field named {} of its own ({:?}); writing {} there would \
             overwrite it",
            f.name, f.description, value.name
        )),
    }
}

/// A 192-byte field descriptor.
fn descriptor(data_type: u8, options: u8, name: &str, description: &str) -> [u8; DESCRIPTOR] {
    let mut d = [0u8; DESCRIPTOR];
    d[2] = data_type;
    d[3] = options;
    // Both fields hold 32 bytes; a longer text is cut, never overruns.
    let name = &name.as_bytes()[..name.len().min(NAME_LEN)];
    let description = &description.as_bytes()[..description.len().min(32)];
    d[NAME_AT..NAME_AT + name.len()].copy_from_slice(name);
    d[DESCRIPTION_AT..DESCRIPTION_AT + description.len()].copy_from_slice(description);
    d
}

/// Where scanmesh's columns go in a LAS output's records, and the Extra
/// Bytes VLR that describes the record's extra bytes.
#[derive(Debug)]
pub(crate) struct ExtraPlan {
    /// Offsets of the normal's x, y, z floats in the record.
    pub(crate) normals_at: Option<usize>,
    /// Offset of each computed value's float in the record, in the
    /// spec's order ([`WriterSpec::values`]).
    pub(crate) values_at: Vec<usize>,
    /// Offset of the flags byte in the record.
    pub(crate) flags_at: Option<usize>,
    /// Bytes of an output record.
    pub(crate) record_len: u16,
    /// The output's Extra Bytes VLR, when it is not the input's as it was.
    pub(crate) vlr: Option<Vlr>,
}

/// The computed fields a LAS output's records carry beside the input's.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Wanted {
    pub(crate) normals: bool,
    pub(crate) values: &'static [ValueField],
    pub(crate) flags: bool,
}

impl Wanted {
    /// What `spec` asks a writer to carry.
    pub(crate) fn of(spec: &WriterSpec) -> Self {
        Wanted {
            normals: spec.with_normals,
            values: spec.values,
            flags: spec.with_flags,
        }
    }
}

/// Plans records of `base` standard bytes followed by the input's `extra`
/// bytes described by `input` (its Extra Bytes VLR, if any), with the
/// `wanted` normals, values and flags: into fields of their names where
/// the input has them, else appended in that order and described.
/// Undescribed input bytes are described as undocumented (type 0) so that
/// what follows them is found. `Err` says why the input's description
/// cannot be extended.
pub(crate) fn plan(
    base: usize,
    extra: usize,
    input: Option<&Vlr>,
    wanted: Wanted,
) -> Result<ExtraPlan, String> {
    let Wanted {
        normals,
        values,
        flags,
    } = wanted;
    let described = match input {
        Some(v) => fields(&v.data)
            .map_err(|t| format!("its Extra Bytes VLR describes a field of unknown type {t}"))?,
        None => Vec::new(),
    };
    let in_place = find_normal_fields(&described, extra).filter(|_| normals);
    let values_in_place = values
        .iter()
        .map(|v| value_in_place(&described, v, extra))
        .collect::<Result<Vec<_>, _>>()?;
    let flags_in_place = find(&described, FLAGS_NAME, U8, extra).filter(|_| flags);
    let add_normals = normals && in_place.is_none();
    let add_values = values_in_place.iter().any(Option::is_none);
    let add_flags = flags && flags_in_place.is_none();
    let mut values_at: Vec<Option<usize>> = values_in_place
        .iter()
        .map(|a| a.map(|a| base + a))
        .collect();
    let mut plan = ExtraPlan {
        normals_at: in_place.map(|n| base + n[0]),
        values_at: Vec::new(),
        flags_at: flags_in_place.map(|f| base + f),
        record_len: 0,
        vlr: None,
    };
    // In place, the normals must be x, y, z in a row, as they are written.
    if let Some(n) = in_place.filter(|n| n[1] != n[0] + 4 || n[2] != n[0] + 8) {
        return Err(format!(
            "its NormalX/Y/Z extra bytes are not consecutive (at {n:?})"
        ));
    }
    let mut len = base + extra;
    if add_normals || add_values || add_flags {
        let total: usize = described.iter().map(|f| f.size).sum();
        if total > extra {
            return Err(format!(
                "its Extra Bytes VLR describes {total} bytes, its records hold {extra}"
            ));
        }
        let mut data = input.map_or_else(Vec::new, |v| v.data.clone());
        let mut undescribed = extra - total;
        while undescribed > 0 {
            let n = undescribed.min(255);
            data.extend(descriptor(
                0,
                n as u8,
                "undescribed",
                "bytes the input left undescribed",
            ));
            undescribed -= n;
        }
        if add_normals {
            plan.normals_at = Some(len);
            len += NORMAL_BYTES;
            for name in NORMAL_NAMES {
                data.extend(descriptor(FLOAT, 0, name, "unit normal (scanmesh)"));
            }
        }
        for (v, at) in values.iter().zip(values_at.iter_mut()) {
            if at.is_none() {
                *at = Some(len);
                len += 4;
                data.extend(descriptor(FLOAT, 0, v.name, v.description));
            }
        }
        if add_flags {
            plan.flags_at = Some(len);
            len += 1;
            data.extend(descriptor(U8, 0, FLAGS_NAME, "1 degenerate, 2 unoriented"));
        }
        if data.len() > usize::from(u16::MAX) {
            return Err(format!(
                "its Extra Bytes VLR would hold {} bytes, more than a VLR can",
                data.len()
            ));
        }
        let header = input.map_or_else(
            || RecordHeader::new(EXTRA_BYTES, "Extra Bytes Record"),
            |v| v.header.clone(),
        );
        plan.vlr = Some(Vlr { header, data });
    }
    // Every value has its place now: the input's field or an appended one.
    plan.values_at = values_at.into_iter().flatten().collect();
    plan.record_len = u16::try_from(len)
        .map_err(|_| format!("its records would be {len} bytes, more than LAS allows"))?;
    Ok(plan)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn both() -> Wanted {
        Wanted {
            normals: true,
            flags: true,
            ..Wanted::default()
        }
    }

    fn normals_only() -> Wanted {
        Wanted {
            normals: true,
            ..Wanted::default()
        }
    }

    const K: ValueField = ValueField {
        name: "k1",
        description: "larger principal curvature",
    };

    /// A value field scanmesh wrote is written in place again; a field of
    /// the same name the input made itself is refused, never overwritten.
    #[test]
    fn a_value_field_of_the_inputs_own_is_not_overwritten() {
        let wanted = Wanted {
            values: std::slice::from_ref(&K),
            ..Wanted::default()
        };
        let mut ours = Vec::new();
        ours.extend(descriptor(FLOAT, 0, "k1", "larger principal curvature"));
        let vlr = |data: Vec<u8>| Vlr {
            header: RecordHeader::new(EXTRA_BYTES, "Extra Bytes Record"),
            data,
        };
        let p = plan(20, 4, Some(&vlr(ours)), wanted).unwrap();
        assert_eq!((p.values_at, p.record_len), (vec![20], 24));
        let theirs = descriptor(FLOAT, 0, "K1", "their own k1").to_vec();
        let e = plan(20, 4, Some(&vlr(theirs)), wanted).unwrap_err();
        assert!(e.contains("field named K1 of its own"), "{e}");
        let other_type = descriptor(U8, 0, "k1", "larger principal curvature").to_vec();
        assert!(plan(20, 1, Some(&vlr(other_type)), wanted).is_err());
    }

    fn described(names: &[(&str, u8)]) -> Vlr {
        let mut data = Vec::new();
        for (name, t) in names {
            data.extend(descriptor(*t, 0, name, ""));
        }
        Vlr {
            header: RecordHeader::new(EXTRA_BYTES, "Extra Bytes Record"),
            data,
        }
    }

    #[test]
    fn new_fields_follow_the_inputs_extra_bytes() {
        let input = described(&[("Amplitude", 9), ("Deviation", 3)]);
        let p = plan(34, 6, Some(&input), both()).unwrap();
        assert_eq!(
            (p.normals_at, p.flags_at, p.record_len),
            (Some(40), Some(52), 53)
        );
        let f = fields(&p.vlr.unwrap().data).unwrap();
        let names: Vec<&str> = f.iter().map(|f| f.name.as_str()).collect();
        assert_eq!(
            names,
            [
                "Amplitude",
                "Deviation",
                "NormalX",
                "NormalY",
                "NormalZ",
                "scanmesh_flags"
            ]
        );
    }

    #[test]
    fn fields_of_scanmeshs_names_are_written_in_place() {
        let input = described(&[
            ("NormalX", 9),
            ("NormalY", 9),
            ("NormalZ", 9),
            ("scanmesh_flags", 1),
        ]);
        let p = plan(30, 13, Some(&input), both()).unwrap();
        assert_eq!(
            (p.normals_at, p.flags_at, p.record_len),
            (Some(30), Some(42), 43)
        );
        assert!(p.vlr.is_none(), "the input's VLR is kept as it is");
    }

    #[test]
    fn undescribed_bytes_are_described_before_new_fields() {
        let p = plan(20, 300, None, normals_only()).unwrap();
        assert_eq!((p.normals_at, p.record_len), (Some(320), 332));
        let f = fields(&p.vlr.unwrap().data).unwrap();
        let sizes: Vec<usize> = f.iter().map(|f| f.size).collect();
        assert_eq!(sizes, [255, 45, 4, 4, 4]);
    }

    #[test]
    fn a_description_longer_than_the_bytes_is_not_extended() {
        let input = described(&[("A", 10)]);
        let e = plan(20, 4, Some(&input), normals_only()).unwrap_err();
        assert!(e.contains("describes 8 bytes"), "{e}");
        // Nothing to add: the input's records are written as they are.
        let p = plan(20, 4, Some(&input), Wanted::default()).unwrap();
        assert_eq!((p.record_len, p.vlr.is_none()), (24, true));
    }
}
