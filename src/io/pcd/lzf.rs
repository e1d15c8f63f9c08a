//! LZF decompression (liblzf's format, used by PCD `binary_compressed`),
//! streaming: back-references reach at most 8 KiB back, so the output goes
//! to a writer and only a window of it stays in memory, whatever the size
//! of the cloud. Written here because the crates that decode LZF want the
//! whole output in memory.

use std::io::{BufRead, Write};

/// Farthest a back-reference reaches (13 bits of offset, plus one).
const REACH: usize = 1 << 13;
/// Output kept in memory before the part beyond [`REACH`] is written out.
const FLUSH_AT: usize = 1 << 20;

/// Decodes `len_in` bytes of `input` into exactly `len_out` bytes on `out`.
pub fn decompress(
    input: &mut dyn BufRead,
    len_in: u64,
    out: &mut dyn Write,
    len_out: u64,
) -> Result<(), String> {
    let mut src = Bytes {
        input,
        left: len_in,
    };
    let mut hist: Vec<u8> = Vec::with_capacity(FLUSH_AT + REACH + 300);
    let mut written = 0u64;
    while src.left > 0 {
        let ctrl = src.next()? as usize;
        if ctrl < 32 {
            for _ in 0..=ctrl {
                hist.push(src.next()?);
            }
        } else {
            let mut len = ctrl >> 5;
            if len == 7 {
                len += src.next()? as usize;
            }
            let back = ((ctrl & 0x1f) << 8) + src.next()? as usize + 1;
            let from = hist
                .len()
                .checked_sub(back)
                .ok_or_else(|| "a back-reference reaches before the data".to_string())?;
            // Byte by byte: the reference may overlap what it writes.
            for k in 0..len + 2 {
                let b = hist[from + k];
                hist.push(b);
            }
        }
        if written + hist.len() as u64 > len_out {
            return Err(format!(
                "decompresses to more than the declared {len_out} bytes"
            ));
        }
        if hist.len() >= FLUSH_AT + REACH {
            let done = hist.len() - REACH;
            out.write_all(&hist[..done]).map_err(|e| e.to_string())?;
            hist.drain(..done);
            written += done as u64;
        }
    }
    out.write_all(&hist).map_err(|e| e.to_string())?;
    written += hist.len() as u64;
    if written != len_out {
        return Err(format!(
            "decompresses to {written} bytes, not the declared {len_out}"
        ));
    }
    Ok(())
}

/// The compressed bytes, one at a time, out of a buffered reader.
struct Bytes<'a> {
    input: &'a mut dyn BufRead,
    left: u64,
}

impl Bytes<'_> {
    #[inline]
    fn next(&mut self) -> Result<u8, String> {
        if self.left == 0 {
            return Err("the compressed data ends inside a run".into());
        }
        let buf = self.input.fill_buf().map_err(|e| e.to_string())?;
        let Some(&b) = buf.first() else {
            return Err("the file ends inside the compressed data".into());
        };
        self.input.consume(1);
        self.left -= 1;
        Ok(b)
    }
}

/// LZF compression with a hash of 3-byte prefixes (greedy, as liblzf):
/// used by tests to make `binary_compressed` bodies.
#[cfg(test)]
pub fn compress(data: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    let mut table = vec![usize::MAX; 1 << 14];
    let mut lit: Vec<u8> = Vec::new();
    let flush = |lit: &mut Vec<u8>, out: &mut Vec<u8>| {
        for run in lit.chunks(32) {
            out.push((run.len() - 1) as u8);
            out.extend_from_slice(run);
        }
        lit.clear();
    };
    let mut i = 0;
    while i < data.len() {
        if i + 2 < data.len() {
            let h = ((data[i] as usize) << 8 ^ (data[i + 1] as usize) << 4 ^ data[i + 2] as usize)
                & ((1 << 14) - 1);
            let cand = table[h];
            table[h] = i;
            if cand != usize::MAX && i - cand <= REACH && data[cand..cand + 3] == data[i..i + 3] {
                let mut len = 3;
                while i + len < data.len() && len < 264 && data[cand + len] == data[i + len] {
                    len += 1;
                }
                flush(&mut lit, &mut out);
                let (l, off) = (len - 2, i - cand - 1);
                if l < 7 {
                    out.push(((l << 5) | (off >> 8)) as u8);
                } else {
                    out.push(((7 << 5) | (off >> 8)) as u8);
                    out.push((l - 7) as u8);
                }
                out.push((off & 0xff) as u8);
                i += len;
                continue;
            }
        }
        lit.push(data[i]);
        i += 1;
    }
    flush(&mut lit, &mut out);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trips_across_the_flush_window() {
        let mut rng = crate::rng::Rng::new(3);
        // Repetitive enough to make long and overlapping references, long
        // enough to be flushed several times.
        let data: Vec<u8> = (0..3_000_000)
            .map(|i| {
                if i % 1000 < 600 {
                    (i % 7) as u8
                } else {
                    rng.below(256) as u8
                }
            })
            .collect();
        let packed = compress(&data);
        assert!(packed.len() < data.len());
        let mut out = Vec::new();
        decompress(
            &mut &packed[..],
            packed.len() as u64,
            &mut out,
            data.len() as u64,
        )
        .unwrap();
        assert!(out == data);
    }

    #[test]
    fn corrupt_streams_are_errors() {
        let packed = compress(b"abcabcabcabcabcabc");
        let n = packed.len() as u64;
        let err = |input: &[u8], len_in: u64, len_out: u64| {
            decompress(&mut &input[..], len_in, &mut Vec::new(), len_out).unwrap_err()
        };
        assert!(err(&packed, n, 5).contains("more than the declared"));
        assert!(err(&packed, n, 50).contains("not the declared 50"));
        assert!(err(&packed[..n as usize - 1], n, 18).contains("file ends"));
        assert!(err(&[0x20, 0x05], 2, 10).contains("before the data"));
        assert!(err(&[0x05, b'a'], 2, 6).contains("ends inside a run"));
    }
}
