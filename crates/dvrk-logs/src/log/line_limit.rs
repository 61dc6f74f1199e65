//! A bound on the length of a text log's lines, so that a file without line breaks
//! (`/dev/zero`, a binary file given as CSV) is refused after [`MAX_LINE_BYTES`] instead
//! of being read into one ever-growing line.

use std::io::{BufRead, Read};

/// The longest line of a text log, bytes: a row of a 100-joint log with every value
/// written to 17 digits is under 10 kB.
pub const MAX_LINE_BYTES: usize = 1 << 20;

/// A [`BufRead`] that fails with [`std::io::ErrorKind::InvalidData`] once a line grows
/// past `limit` bytes; the error names the line (1-based).
pub(crate) struct LineLimit<R> {
    inner: R,
    limit: usize,
    /// Line being read, 1-based.
    line: u64,
    /// Bytes of that line consumed so far.
    run: usize,
}

impl<R: BufRead> LineLimit<R> {
    pub(crate) fn new(inner: R, limit: usize) -> LineLimit<R> {
        LineLimit {
            inner,
            limit,
            line: 1,
            run: 0,
        }
    }
}

impl<R: BufRead> Read for LineLimit<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = {
            let available = self.fill_buf()?;
            let n = available.len().min(buf.len());
            buf[..n].copy_from_slice(&available[..n]);
            n
        };
        self.consume(n);
        Ok(n)
    }
}

impl<R: BufRead> BufRead for LineLimit<R> {
    fn fill_buf(&mut self) -> std::io::Result<&[u8]> {
        if self.run > self.limit {
            return Err(std::io::Error::new(
                std::io::ErrorKind::InvalidData,
                format!(
                    "line {} is longer than {} bytes: not a text log (one sample per line)",
                    self.line, self.limit
                ),
            ));
        }
        self.inner.fill_buf()
    }

    fn consume(&mut self, amount: usize) {
        if amount == 0 {
            return;
        }
        // The bytes consumed are the front of the inner buffer, which `fill_buf` returns
        // again without reading while it is not empty.
        if let Ok(buf) = self.inner.fill_buf() {
            let consumed = &buf[..amount.min(buf.len())];
            match consumed.iter().rposition(|&b| b == b'\n') {
                Some(last) => {
                    self.line += consumed.iter().filter(|&&b| b == b'\n').count() as u64;
                    self.run = consumed.len() - last - 1;
                }
                None => self.run += consumed.len(),
            }
        }
        self.inner.consume(amount);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_lines_are_refused_with_their_number() {
        let text = format!("a,b\n1,2\n{}\n", "9".repeat(100));
        let mut r = LineLimit::new(std::io::BufReader::with_capacity(8, text.as_bytes()), 50);
        let mut out = String::new();
        let e = r.read_to_string(&mut out).unwrap_err();
        assert!(
            e.to_string().contains("line 3 is longer than 50 bytes"),
            "{e}"
        );
        // Lines up to the limit pass whole.
        let text = format!("{}\n{}\n", "1".repeat(50), "2".repeat(50));
        let mut r = LineLimit::new(std::io::BufReader::with_capacity(8, text.as_bytes()), 50);
        let mut out = String::new();
        r.read_to_string(&mut out).unwrap();
        assert_eq!(out, text);
    }

    #[test]
    fn dev_zero_ends() {
        let file = std::fs::File::open("/dev/zero").unwrap();
        let mut r = LineLimit::new(std::io::BufReader::new(file), MAX_LINE_BYTES);
        let mut sink = Vec::new();
        let e = r.read_to_end(&mut sink).unwrap_err();
        assert!(e.to_string().contains("line 1 is longer"), "{e}");
        assert!(sink.len() <= MAX_LINE_BYTES + (64 << 10));
    }
}
