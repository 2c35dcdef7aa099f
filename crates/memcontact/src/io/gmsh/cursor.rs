//! A cursor over an MSH file: whitespace-separated tokens for the text parts, little- or
//! big-endian numbers for the binary ones.

/// A cursor over the file: whitespace-separated tokens for the text parts, little- or
/// big-endian numbers for the binary ones.
pub(super) struct Cursor<'a> {
    pub(super) buf: &'a [u8],
    pub(super) pos: usize,
    /// Binary numbers are byte-swapped (the file was written on the other endianness).
    pub(super) swap: bool,
    /// Size of `size_t` in 4.1 binary files.
    pub(super) size_t: usize,
    /// The section being read, for messages.
    pub(super) section: &'static str,
}

pub(super) type Parse<T> = std::result::Result<T, String>;

impl<'a> Cursor<'a> {
    pub(super) fn line(&self, pos: usize) -> usize {
        1 + self.buf[..pos.min(self.buf.len())]
            .iter()
            .filter(|&&b| b == b'\n')
            .count()
    }

    /// The next whitespace-separated token and the line it is on.
    pub(super) fn token(&mut self) -> Option<(&'a str, usize)> {
        while self.pos < self.buf.len() && self.buf[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        if self.pos >= self.buf.len() {
            return None;
        }
        let start = self.pos;
        while self.pos < self.buf.len() && !self.buf[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        let text = std::str::from_utf8(&self.buf[start..self.pos]).unwrap_or("<not text>");
        Some((text, start))
    }

    /// The next token parsed as `T`, `what` naming it in the error.
    pub(super) fn parse<T: std::str::FromStr>(&mut self, what: &str) -> Parse<T> {
        match self.token() {
            Some((text, start)) => text.parse().map_err(|_| {
                format!(
                    "line {} ({}): expected {what}, found `{}`",
                    self.line(start),
                    self.section,
                    text.chars().take(40).collect::<String>()
                )
            }),
            None => Err(format!(
                "unexpected end of file in {}: expected {what}",
                self.section
            )),
        }
    }

    /// Requires the token `word` (a section end, ...).
    pub(super) fn expect(&mut self, word: &str) -> Parse<()> {
        match self.token() {
            Some((t, _)) if t == word => Ok(()),
            Some((t, start)) => Err(format!(
                "line {}: expected `{word}`, found `{}`",
                self.line(start),
                t.chars().take(40).collect::<String>()
            )),
            None => Err(format!("unexpected end of file: expected `{word}`")),
        }
    }

    /// Skips the rest of the current line, its newline included (binary data follows).
    pub(super) fn end_line(&mut self) {
        while self.pos < self.buf.len() && self.buf[self.pos] != b'\n' {
            self.pos += 1;
        }
        self.pos = (self.pos + 1).min(self.buf.len());
    }

    /// The next `len` bytes of binary data (`what` names them in the error).
    pub(super) fn take(&mut self, len: usize, what: &str) -> Parse<&'a [u8]> {
        let end = self.pos.saturating_add(len);
        if end > self.buf.len() {
            return Err(format!(
                "unexpected end of file in the binary data of {} (byte {}): expected {what}",
                self.section, self.pos
            ));
        }
        let b = &self.buf[self.pos..end];
        self.pos = end;
        Ok(b)
    }

    pub(super) fn bytes<const N: usize>(&mut self, what: &str) -> Parse<[u8; N]> {
        Ok(Binary::of(self).array(self.take(N, what)?))
    }

    pub(super) fn int(&mut self, what: &str) -> Parse<i32> {
        Ok(i32::from_ne_bytes(self.bytes::<4>(what)?))
    }

    pub(super) fn double(&mut self, what: &str) -> Parse<f64> {
        Ok(f64::from_ne_bytes(self.bytes::<8>(what)?))
    }

    pub(super) fn size(&mut self, what: &str) -> Parse<u64> {
        let b = Binary::of(self);
        Ok(b.size(self.take(b.size_t, what)?))
    }

    /// A count the rest of the file can hold, each item taking at least `min_bytes` bytes
    /// (separators included): what is reserved for the items is bounded by a small multiple
    /// of the file's size, never by a declared count alone.
    pub(super) fn check_count(&self, n: u64, min_bytes: u64, what: &str) -> Parse<usize> {
        let rest = (self.buf.len() - self.pos.min(self.buf.len())) as u64 + 1;
        if n > rest / min_bytes.max(1) {
            return Err(format!(
                "{}: {what} = {n} is more than the file can hold (truncated or corrupt file?)",
                self.section
            ));
        }
        Ok(n as usize)
    }
}

/// How binary numbers are stored: byte order and the size of `size_t`. Decodes numbers
/// from slices, so that the fixed-size records of a block can be read in parallel.
#[derive(Clone, Copy)]
pub(super) struct Binary {
    pub(super) swap: bool,
    pub(super) size_t: usize,
}

impl Binary {
    pub(super) fn of(c: &Cursor) -> Binary {
        Binary {
            swap: c.swap,
            size_t: c.size_t,
        }
    }

    /// The `N` bytes of `b` (exactly `N` long) in native order.
    #[inline(always)]
    pub(super) fn array<const N: usize>(self, b: &[u8]) -> [u8; N] {
        let mut a: [u8; N] = b.try_into().expect("length N");
        if self.swap {
            a.reverse();
        }
        a
    }

    /// A `size_t` from its `size_t` bytes.
    #[inline(always)]
    pub(super) fn size(self, b: &[u8]) -> u64 {
        if self.size_t == 4 {
            u32::from_ne_bytes(self.array(b)) as u64
        } else {
            u64::from_ne_bytes(self.array(b))
        }
    }

    #[inline(always)]
    pub(super) fn double(self, b: &[u8]) -> f64 {
        f64::from_ne_bytes(self.array(b))
    }
}

/// Records per task when the records of a binary block are decoded in parallel.
pub(super) const RECORDS_PER_TASK: usize = 8192;

pub(super) fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    hay.windows(needle.len()).position(|w| w == needle)
}
