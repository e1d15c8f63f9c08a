//! PNG writing (8-bit RGB, one IDAT chunk compressed by flate2's zlib, rows
//! filtered with "Sub"), and the reading back of such files for tests. A
//! few dozen lines, so no image crate: the format is IHDR, IDAT, IEND
//! chunks, each with a CRC-32 (flate2's, the same polynomial).

use crate::io::{AtomicFile, IoError};
use flate2::write::ZlibEncoder;
use flate2::Compression;
use std::io::Write;
use std::path::Path;

const SIGNATURE: [u8; 8] = [137, 80, 78, 71, 13, 10, 26, 10];

fn chunk(out: &mut Vec<u8>, kind: &[u8; 4], data: &[u8]) {
    out.extend_from_slice(&(data.len() as u32).to_be_bytes());
    let mut crc = flate2::Crc::new();
    crc.update(kind);
    crc.update(data);
    out.extend_from_slice(kind);
    out.extend_from_slice(data);
    out.extend_from_slice(&crc.sum().to_be_bytes());
}

/// The PNG bytes of a `width x height` RGB image, rows top to bottom.
pub fn encode_rgb(width: usize, height: usize, rgb: &[[u8; 3]]) -> Vec<u8> {
    let mut raw = Vec::with_capacity(height * (1 + 3 * width));
    for row in rgb.chunks(width.max(1)).take(height) {
        raw.push(1); // Sub: each byte minus the one a pixel to its left.
        let mut left = [0u8; 3];
        for px in row {
            for c in 0..3 {
                raw.push(px[c].wrapping_sub(left[c]));
            }
            left = *px;
        }
    }
    let mut z = ZlibEncoder::new(Vec::new(), Compression::default());
    // Writing to a Vec cannot fail.
    let _ = z.write_all(&raw);
    let idat = z.finish().unwrap_or_default();
    let mut ihdr = Vec::with_capacity(13);
    ihdr.extend_from_slice(&(width as u32).to_be_bytes());
    ihdr.extend_from_slice(&(height as u32).to_be_bytes());
    ihdr.extend_from_slice(&[8, 2, 0, 0, 0]);
    let mut out = SIGNATURE.to_vec();
    chunk(&mut out, b"IHDR", &ihdr);
    chunk(&mut out, b"IDAT", &idat);
    chunk(&mut out, b"IEND", &[]);
    out
}

/// Writes an RGB image as PNG (appears under its name only when complete).
pub fn write_rgb(path: &Path, width: usize, height: usize, rgb: &[[u8; 3]]) -> Result<(), IoError> {
    let bytes = encode_rgb(width, height, rgb);
    let mut file = AtomicFile::create(path)?;
    file.file()
        .write_all(&bytes)
        .map_err(|e| IoError::os(path, e))?;
    file.commit()
}

/// Decodes what [`encode_rgb`] writes (8-bit RGB, filters None and Sub):
/// width, height and pixels; `None` for anything else.
#[cfg(test)]
pub fn decode_rgb(bytes: &[u8]) -> Option<(usize, usize, Vec<[u8; 3]>)> {
    use std::io::Read;
    if bytes.get(..8)? != SIGNATURE {
        return None;
    }
    let (mut at, mut size, mut idat) = (8, None, Vec::new());
    while at + 12 <= bytes.len() {
        let len = u32::from_be_bytes(bytes[at..at + 4].try_into().ok()?) as usize;
        let kind = &bytes[at + 4..at + 8];
        let data = bytes.get(at + 8..at + 8 + len)?;
        let mut crc = flate2::Crc::new();
        crc.update(kind);
        crc.update(data);
        if crc.sum().to_be_bytes() != bytes.get(at + 8 + len..at + 12 + len)? {
            return None;
        }
        match kind {
            b"IHDR" if data[8..13] == [8, 2, 0, 0, 0] => {
                let w = u32::from_be_bytes(data[0..4].try_into().ok()?) as usize;
                let h = u32::from_be_bytes(data[4..8].try_into().ok()?) as usize;
                size = Some((w, h));
            }
            b"IDAT" => idat.extend_from_slice(data),
            _ => {}
        }
        at += 12 + len;
    }
    let (w, h) = size?;
    let mut raw = Vec::new();
    flate2::read::ZlibDecoder::new(&idat[..])
        .read_to_end(&mut raw)
        .ok()?;
    let mut px = Vec::with_capacity(w * h);
    for row in raw.chunks(1 + 3 * w).take(h) {
        let mut left = [0u8; 3];
        for p in row[1..].chunks_exact(3) {
            let v = match row[0] {
                0 => [p[0], p[1], p[2]],
                1 => [0, 1, 2].map(|c| p[c].wrapping_add(left[c])),
                _ => return None,
            };
            px.push(v);
            left = v;
        }
    }
    (px.len() == w * h).then_some((w, h, px))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trips_through_zlib_and_crc() {
        let (w, h) = (37, 11);
        let px: Vec<[u8; 3]> = (0..w * h)
            .map(|i| [(i * 7) as u8, (i * 13 + 5) as u8, (i / 3) as u8])
            .collect();
        let bytes = encode_rgb(w, h, &px);
        assert_eq!(decode_rgb(&bytes), Some((w, h, px)));
        // A flipped bit fails its chunk's CRC.
        let mut bad = bytes.clone();
        bad[40] ^= 1;
        assert_eq!(decode_rgb(&bad), None);
    }
}
