//! Opening an input file: gzip is recognised by its magic bytes (not by name)
//! and decompressed transparently, and the first bytes of the inner content
//! are kept so formats can be sniffed by content.

use super::{IoError, Trailing};
use flate2::read::MultiGzDecoder;
use std::fs::File;
use std::io::{self, BufRead, BufReader, Chain, Cursor, Read};
use std::path::Path;

/// A buffered byte stream over the (decompressed) content of a file.
pub(crate) type Input = Box<dyn BufRead + Send>;

/// Bytes kept for sniffing: enough for `ply\r\n`, `LASF` and the gzip magic.
const MAGIC_LEN: usize = 8;
/// Read buffer size: large sequential reads keep syscalls and gzip calls rare.
pub(crate) const BUF_CAPACITY: usize = 1 << 18;
const GZIP_MAGIC: [u8; 2] = [0x1f, 0x8b];

pub(crate) struct Opened {
    pub input: Input,
    pub gzip: bool,
    /// First bytes of the decompressed content (fewer only if it is shorter).
    pub magic: Vec<u8>,
}

/// Opens `path`, unwrapping gzip (also multi-member gzip) when present.
/// An empty file, or a gzip stream of nothing, is [`IoError::Empty`].
pub(crate) fn open_input(path: &Path) -> Result<Opened, IoError> {
    let file = File::open(path).map_err(|e| IoError::os(path, e))?;
    open_stream(path, file)
}

/// Like [`open_input`] over any byte stream; `path` names it in errors.
pub(crate) fn open_stream(
    path: &Path,
    stream: impl Read + Send + 'static,
) -> Result<Opened, IoError> {
    let os = |e| IoError::os(path, e);
    let (magic, rest) = peek(stream).map_err(os)?;
    if magic.is_empty() {
        return Err(IoError::Empty {
            path: path.to_path_buf(),
        });
    }
    if !magic.starts_with(&GZIP_MAGIC) {
        return Ok(Opened {
            input: Box::new(BufReader::with_capacity(BUF_CAPACITY, rest)),
            gzip: false,
            magic,
        });
    }
    let gz = MultiGzDecoder::new(BufReader::with_capacity(BUF_CAPACITY, rest));
    let (magic, inner) = peek(gz).map_err(os)?;
    if magic.is_empty() {
        return Err(IoError::Empty {
            path: path.to_path_buf(),
        });
    }
    Ok(Opened {
        input: Box::new(BufReader::with_capacity(BUF_CAPACITY, inner)),
        gzip: true,
        magic,
    })
}

/// A stream with its first bytes put back in front.
type Rewound<R> = Chain<Cursor<Vec<u8>>, R>;

/// Reads up to [`MAGIC_LEN`] bytes and hands back a stream that still starts
/// at the first byte (a single `read` may return less than asked, notably
/// from a gzip decoder, hence the loop).
fn peek<R: Read>(mut r: R) -> io::Result<(Vec<u8>, Rewound<R>)> {
    let mut buf = vec![0u8; MAGIC_LEN];
    let got = read_full(&mut r, &mut buf)?;
    buf.truncate(got);
    Ok((buf.clone(), Cursor::new(buf).chain(r)))
}

/// Fills `buf` as far as the stream allows; returns the bytes read, which is
/// less than `buf.len()` only at end of stream.
pub(crate) fn read_full<R: Read + ?Sized>(r: &mut R, buf: &mut [u8]) -> io::Result<usize> {
    let mut got = 0;
    while got < buf.len() {
        match r.read(&mut buf[got..]) {
            Ok(0) => break,
            Ok(k) => got += k,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(e),
        }
    }
    Ok(got)
}

/// Discards exactly `n` bytes; returns how many were there before the end.
pub(crate) fn skip_bytes<R: Read + ?Sized>(r: &mut R, n: u64) -> io::Result<u64> {
    io::copy(&mut Read::take(&mut *r, n), &mut io::sink())
}

/// Bytes counted past the first non-zero byte of a tail at most: enough
/// to say how much follows, without reading a huge file to its end to
/// word an error.
const TAIL_COUNT_CAP: u64 = 1 << 26;

/// What follows the declared data of a binary body, when it is data.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Tail {
    /// Bytes after the declared data (all of them when `exact`, else at
    /// least this many).
    pub bytes: u64,
    pub exact: bool,
}

impl Tail {
    /// The tail as an error says what follows the declared data: its size
    /// and, for a body of `record`-byte records, how many whole records it
    /// would hold.
    pub fn found(&self, record: Option<u64>) -> Trailing {
        Trailing::Bytes {
            bytes: self.bytes,
            exact: self.exact,
            record,
        }
    }
}

/// Reads `r` to its end after the declared data of a binary body: `None`
/// when nothing follows, or only zero bytes (padding: PCL pads its binary
/// PCD files with zeros, and zeros cannot be told from padding anyway),
/// else how much follows.
pub(crate) fn binary_tail<R: Read + ?Sized>(r: &mut R) -> io::Result<Option<Tail>> {
    let mut buf = vec![0u8; 1 << 16];
    let mut bytes = 0u64;
    let mut data_at = None;
    loop {
        let n = match r.read(&mut buf) {
            Ok(0) => break,
            Ok(n) => n,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(e),
        };
        if data_at.is_none() && buf[..n].iter().any(|&b| b != 0) {
            data_at = Some(bytes);
        }
        bytes += n as u64;
        if data_at.is_some_and(|at| bytes - at > TAIL_COUNT_CAP) {
            return Ok(Some(Tail {
                bytes,
                exact: false,
            }));
        }
    }
    Ok(data_at.map(|_| Tail { bytes, exact: true }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_tail_of_zeros_is_padding_any_other_byte_is_data() {
        assert_eq!(binary_tail(&mut &b""[..]).unwrap(), None);
        assert_eq!(binary_tail(&mut &[0u8; 5000][..]).unwrap(), None);
        let mut tail = vec![0u8; 70_000];
        tail[69_999] = 1;
        let t = binary_tail(&mut &tail[..]).unwrap().unwrap();
        assert_eq!(
            t,
            Tail {
                bytes: 70_000,
                exact: true
            }
        );
        assert_eq!(
            Tail {
                bytes: 30,
                exact: true
            }
            .found(Some(12))
            .to_string(),
            "30 bytes follow the declared data, 2 whole records of 12 bytes and 6 bytes"
        );
    }
}
