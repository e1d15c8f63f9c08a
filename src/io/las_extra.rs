//! Normals in LAS "extra bytes": the Extra Bytes VLR (`LASF_Spec`, record
//! 4; ASPRS LAS 1.4 R15 sec. 2.5.3.2) describes fields that follow the
//! standard point record, 192 bytes a field. scanmesh writes normals as three
//! float fields named `NormalX`, `NormalY`, `NormalZ` (PDAL's names for the
//! same dimensions) and reads them back from any file that describes them so.

use las::{Header, Vlr};

const USER: &str = "LASF_Spec";
const RECORD: u16 = 4;
const DESCRIPTOR: usize = 192;
const NAME_AT: usize = 4;
const NAME_LEN: usize = 32;
/// Data type 9: f32.
const FLOAT: u8 = 9;
const NAMES: [&str; 3] = ["NormalX", "NormalY", "NormalZ"];

/// Bytes the normals take at the end of each record.
pub(crate) const NORMAL_BYTES: u16 = 12;

/// The VLR describing three float normal fields.
pub(crate) fn normals_vlr() -> Vlr {
    let mut data = vec![0u8; DESCRIPTOR * 3];
    for (d, name) in data.chunks_exact_mut(DESCRIPTOR).zip(NAMES) {
        d[2] = FLOAT;
        d[NAME_AT..NAME_AT + name.len()].copy_from_slice(name.as_bytes());
        let desc = b"unit normal (scanmesh)";
        d[160..160 + desc.len()].copy_from_slice(desc);
    }
    Vlr {
        user_id: USER.into(),
        record_id: RECORD,
        description: "Extra Bytes Record".into(),
        data,
    }
}

/// Byte size of a described field (type 0: `options` bytes, undocumented).
fn field_size(data_type: u8, options: u8) -> Option<usize> {
    Some(match data_type {
        0 => usize::from(options),
        1 | 2 => 1,
        3 | 4 => 2,
        5 | 6 | 9 => 4,
        7 | 8 | 10 => 8,
        _ => return None,
    })
}

/// Offsets of `NormalX/Y/Z` within the extra bytes, when the header
/// describes all three as floats inside the record's extra bytes.
pub(crate) fn find_normals(header: &Header) -> Option<[usize; 3]> {
    let extra = usize::from(header.point_format().extra_bytes);
    let vlr = header
        .all_vlrs()
        .find(|v| v.user_id == USER && v.record_id == RECORD)?;
    let mut at = 0usize;
    let mut found = [None; 3];
    for d in vlr.data.chunks_exact(DESCRIPTOR) {
        let size = field_size(d[2], d[3])?;
        let raw = &d[NAME_AT..NAME_AT + NAME_LEN];
        let name = String::from_utf8_lossy(raw.split(|&b| b == 0).next().unwrap_or(raw));
        if let Some(k) = NAMES.iter().position(|n| n.eq_ignore_ascii_case(&name)) {
            if d[2] == FLOAT && at + 4 <= extra {
                found[k] = Some(at);
            }
        }
        at += size;
    }
    match found {
        [Some(x), Some(y), Some(z)] => Some([x, y, z]),
        _ => None,
    }
}
