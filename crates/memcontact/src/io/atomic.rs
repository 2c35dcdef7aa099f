//! Atomic file writes: write to a temporary file beside the target, then rename, so that a
//! failed run never leaves a half-written output behind. The bytes are counted and hashed
//! as they are written ([`Written`]), so a result set's manifest never reads its files back.

use super::direct_writer::Staged;
use crate::error::{Error, Result};
use std::io::Write;
use std::path::Path;

/// The size and XXH3-64 digest of a file's bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Written {
    /// Bytes written.
    pub bytes: u64,
    /// XXH3-64 of the bytes.
    pub xxh3: u64,
}

impl Written {
    /// The digest as 16 hex digits (how `summary.json` and `manifest.json` record it).
    pub fn hex(&self) -> String {
        format!("{:016x}", self.xxh3)
    }
}

/// A writer that counts and hashes the bytes it passes on.
struct Hashing<W: Write> {
    inner: W,
    hasher: xxhash_rust::xxh3::Xxh3,
    bytes: u64,
}

impl<W: Write> Write for Hashing<W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let n = self.inner.write(buf)?;
        self.hasher.update(&buf[..n]);
        self.bytes += n as u64;
        Ok(n)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush()
    }
}

/// Writes `path` atomically: `fill` writes into a temporary file in the same directory
/// (through staging buffers and a writer thread), which is synced and renamed
/// over `path` only if `fill` and every write succeed. Returns the size and digest of what
/// was written.
pub fn write_atomic(
    path: &Path,
    fill: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> Result<Written> {
    let io_err = |source| Error::Io {
        path: path.to_path_buf(),
        source,
    };
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => std::path::PathBuf::from("."),
    };
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "output".into());
    let tmp = dir.join(format!(".{name}.tmp{}", std::process::id()));
    let result = (|| {
        let file = std::fs::File::create(&tmp)?;
        let mut w = Hashing {
            inner: Staged::new(file),
            hasher: xxhash_rust::xxh3::Xxh3::new(),
            bytes: 0,
        };
        fill(&mut w)?;
        w.flush()?;
        let written = Written {
            bytes: w.bytes,
            xxh3: w.hasher.digest(),
        };
        w.inner.finish()?.sync_all()?;
        std::fs::rename(&tmp, path)?;
        Ok(written)
    })();
    result.map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        io_err(e)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A file of several staging buffers (and a tail) is written whole, with the digest
    /// of its bytes.
    #[test]
    fn large_file_written_in_staging_buffers_is_whole() {
        let tmp = tempfile::tempdir().unwrap();
        let p = tmp.path().join("big.bin");
        let data: Vec<u8> = (0..(5 * super::super::direct_writer::STAGE as u64 + 12_345))
            .map(|i| (i % 253) as u8)
            .collect();
        let written = write_atomic(&p, |w| {
            for chunk in data.chunks(300_001) {
                w.write_all(chunk)?;
            }
            Ok(())
        })
        .unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), data);
        assert_eq!(written.bytes, data.len() as u64);
        assert_eq!(written.xxh3, xxhash_rust::xxh3::xxh3_64(&data));
    }

    #[test]
    fn failed_write_leaves_nothing() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path();
        let p = dir.join("a.txt");
        let written = write_atomic(&p, |w| w.write_all(b"hello")).unwrap();
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "hello");
        // The digest is that of the bytes on disk, computed independently.
        assert_eq!(written.bytes, 5);
        assert_eq!(written.xxh3, xxhash_rust::xxh3::xxh3_64(b"hello"));
        let q = dir.join("b.txt");
        let r = write_atomic(&q, |w| {
            w.write_all(b"half")?;
            Err(std::io::Error::other("boom"))
        });
        assert!(r.is_err());
        assert!(!q.exists());
        assert_eq!(std::fs::read_dir(dir).unwrap().count(), 1);
    }
}
