//! A read buffer that survives seeks. The e57 crate seeks before reading
//! each 1 KiB page (to the position it is already at, when it streams), and
//! `std::io::BufReader` drops its buffer on every seek: two system calls
//! per page. Here a seek only moves the position; a read is served from
//! the buffer when it holds the position, else the buffer is refilled
//! there with one positioned read.

use std::fs::File;
use std::io::{self, Read, Seek, SeekFrom};
use std::os::unix::fs::FileExt;

const CAPACITY: usize = 1 << 18;

pub struct SeekBuf<F> {
    file: F,
    len: u64,
    pos: u64,
    buf: Vec<u8>,
    /// File offset of `buf[0]`.
    start: u64,
}

impl SeekBuf<File> {
    pub fn new(file: File) -> Self {
        let len = file.metadata().map(|m| m.len()).unwrap_or(0);
        SeekBuf {
            file,
            len,
            pos: 0,
            buf: Vec::new(),
            start: 0,
        }
    }
}

impl<F: FileExt> Read for SeekBuf<F> {
    fn read(&mut self, out: &mut [u8]) -> io::Result<usize> {
        let end = self.start + self.buf.len() as u64;
        if self.pos < self.start || self.pos >= end {
            self.buf.resize(CAPACITY, 0);
            let got = self.file.read_at(&mut self.buf, self.pos)?;
            self.buf.truncate(got);
            self.start = self.pos;
            if got == 0 {
                return Ok(0);
            }
        }
        let at = (self.pos - self.start) as usize;
        let n = out.len().min(self.buf.len() - at);
        out[..n].copy_from_slice(&self.buf[at..at + n]);
        self.pos += n as u64;
        Ok(n)
    }
}

impl<F> Seek for SeekBuf<F> {
    fn seek(&mut self, to: SeekFrom) -> io::Result<u64> {
        let target = match to {
            SeekFrom::Start(p) => Some(p),
            SeekFrom::End(d) => self.len.checked_add_signed(d),
            SeekFrom::Current(d) => self.pos.checked_add_signed(d),
        };
        match target {
            Some(p) => {
                self.pos = p;
                Ok(p)
            }
            None => Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                "seek before the start of the file",
            )),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    #[test]
    fn reads_after_seeks_equal_the_file() {
        let mut f = tempfile::tempfile().unwrap();
        let data: Vec<u8> = (0..700_000u32).map(|i| (i * 7 % 251) as u8).collect();
        f.write_all(&data).unwrap();
        let mut r = SeekBuf::new(f);
        for &at in &[0u64, 5, 300_000, 299_999, 699_990, 1] {
            r.seek(SeekFrom::Start(at)).unwrap();
            let mut got = vec![0u8; 20];
            let n = r.read(&mut got).unwrap();
            let end = (at as usize + n).min(data.len());
            assert_eq!(&got[..n], &data[at as usize..end]);
            assert!(n > 0);
        }
        r.seek(SeekFrom::End(0)).unwrap();
        assert_eq!(r.read(&mut [0u8; 4]).unwrap(), 0);
        assert!(r.seek(SeekFrom::Current(-1_000_000)).is_err());
    }
}
