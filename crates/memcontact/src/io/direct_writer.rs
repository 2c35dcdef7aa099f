//! A file written through two staging buffers and a writer thread, with direct I/O where
//! the file system allows it.
//!
//! Large results (the node table and the VTU of a multi-million-vertex mesh are gigabytes)
//! would otherwise pass through the page cache: gigabytes of kernel memory taken for bytes
//! the run never reads again, which on a virtual machine costs as much to obtain as the
//! solver's own memory. Written with `O_DIRECT` they go from the staging buffer to the disk,
//! and the writer thread overlaps that transfer with the formatting of the next buffer.
//!
//! The policy, in one place:
//! - A file smaller than one buffer never starts the thread; it is written at the end, buffered.
//! - Full buffers are written by the thread, with `O_DIRECT` on Linux when the file system
//!   accepts it ([`set_direct`]). Otherwise, or if a direct write is refused, buffered writes
//!   with a hint to start the writeback ([`start_writeback`]), so the closing `fsync` finds
//!   the bytes on disk already.
//! - The tail (less than one buffer, of any length) is written buffered after the thread ends.

use std::fs::File;
use std::io::{Seek, SeekFrom, Write};
use std::sync::mpsc::{sync_channel, Receiver, SyncSender};
use std::thread::JoinHandle;

/// Bytes in one staging buffer: a multiple of [`ALIGN`], large enough that one direct write
/// keeps the disk busy, small enough that the two buffers of each file stay in cache-warm
/// memory that is reused.
pub(crate) const STAGE: usize = 4 << 20;

/// Alignment of buffer addresses and file offsets for direct I/O (the largest logical block
/// size in use).
const ALIGN: usize = 4096;

/// A buffer of up to [`STAGE`] bytes whose start is [`ALIGN`]-aligned: a vector reserved
/// once with room for the padding and the bytes, never grown past it (so it never moves).
/// Only the bytes written are touched: a small file costs no more memory than its size.
struct Buffer {
    bytes: Vec<u8>,
    /// Padding before the aligned start.
    start: usize,
}

impl Buffer {
    fn new() -> Buffer {
        let mut bytes: Vec<u8> = Vec::with_capacity(STAGE + ALIGN);
        let start = bytes.as_ptr().align_offset(ALIGN);
        bytes.resize(start, 0);
        Buffer { bytes, start }
    }

    /// Bytes held.
    fn len(&self) -> usize {
        self.bytes.len() - self.start
    }

    /// Appends as much of `data` as fits; returns how much.
    fn fill(&mut self, data: &[u8]) -> usize {
        let n = data.len().min(STAGE - self.len());
        self.bytes.extend_from_slice(&data[..n]);
        n
    }

    /// The bytes held, from the aligned start.
    fn data(&self) -> &[u8] {
        &self.bytes[self.start..]
    }

    /// Empties the buffer for reuse.
    fn clear(&mut self) {
        self.bytes.truncate(self.start);
    }
}

/// The writer thread of a [`Staged`] file: full buffers go to it, written buffers come back.
struct Writer {
    full: SyncSender<Buffer>,
    empty: Receiver<Buffer>,
    thread: JoinHandle<std::io::Result<(File, u64)>>,
}

/// A file written through staging buffers (see the module documentation). Call
/// [`Staged::finish`] to write the tail and get the file back; dropping it without
/// finishing abandons the bytes not yet written.
pub(crate) struct Staged {
    /// The file, until the writer thread takes it.
    file: Option<File>,
    /// The buffer being filled.
    buf: Option<Buffer>,
    writer: Option<Writer>,
}

impl Staged {
    /// A staged writer for `file`, which must be empty and opened for writing.
    pub(crate) fn new(file: File) -> Staged {
        Staged {
            file: Some(file),
            buf: None,
            writer: None,
        }
    }

    /// Hands the full buffer to the writer thread (started on the first call) and takes an
    /// empty one back.
    fn pass_full(&mut self) -> std::io::Result<()> {
        let full = self.buf.take().expect("a buffer is being filled");
        let starting = self.writer.is_none();
        let writer = match &mut self.writer {
            Some(w) => w,
            None => {
                // The file is here until the thread starts, and gone only after a failure.
                let Some(file) = self.file.take() else {
                    return Err(failed_before());
                };
                let (full_tx, full_rx) = sync_channel::<Buffer>(1);
                let (empty_tx, empty_rx) = sync_channel::<Buffer>(2);
                let thread = std::thread::Builder::new()
                    .name("memcontact-writer".into())
                    .spawn(move || write_buffers(file, full_rx, empty_tx))?;
                self.writer.insert(Writer {
                    full: full_tx,
                    empty: empty_rx,
                    thread,
                })
            }
        };
        if writer.full.send(full).is_err() {
            return Err(self.writer_error());
        }
        // The second buffer is made when the thread starts; from then on the two take turns.
        if starting {
            self.buf = Some(Buffer::new());
            return Ok(());
        }
        match writer.empty.recv() {
            Ok(mut b) => {
                b.clear();
                self.buf = Some(b);
                Ok(())
            }
            Err(_) => Err(self.writer_error()),
        }
    }

    /// The error that stopped the writer thread (it returns it when joined).
    fn writer_error(&mut self) -> std::io::Error {
        match self.writer.take() {
            Some(w) => {
                drop(w.full);
                match w.thread.join() {
                    Ok(Err(e)) => e,
                    Ok(Ok(_)) => std::io::Error::other("the file writer stopped early"),
                    Err(_) => std::io::Error::other("the file writer panicked"),
                }
            }
            None => std::io::Error::other("the file writer is gone"),
        }
    }

    /// Writes what is left, waits for the writer thread and returns the file, positioned
    /// at its end. The caller syncs it.
    pub(crate) fn finish(mut self) -> std::io::Result<File> {
        let (mut file, offset) = match self.writer.take() {
            None => match self.file.take() {
                Some(f) => (f, 0),
                None => return Err(failed_before()),
            },
            Some(w) => {
                drop(w.full);
                match w.thread.join() {
                    Ok(r) => r?,
                    Err(_) => return Err(std::io::Error::other("the file writer panicked")),
                }
            }
        };
        set_direct(&file, false)?;
        file.seek(SeekFrom::Start(offset))?;
        if let Some(buf) = &self.buf {
            file.write_all(buf.data())?;
        }
        Ok(file)
    }
}

impl Write for Staged {
    fn write(&mut self, data: &[u8]) -> std::io::Result<usize> {
        if data.is_empty() {
            return Ok(0);
        }
        let buf = self.buf.get_or_insert_with(Buffer::new);
        let n = buf.fill(data);
        if buf.len() == STAGE {
            self.pass_full()?;
        }
        Ok(n)
    }

    /// Buffers are written when full or at [`Staged::finish`]; nothing to do before.
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

/// The error of a write or finish after the writer thread failed (its own error was
/// returned then).
fn failed_before() -> std::io::Error {
    std::io::Error::other("an earlier write to the file failed")
}

/// The writer thread: writes each full buffer at the next offset and sends it back, until
/// the sending side closes. Returns the file and the bytes written.
fn write_buffers(
    mut file: File,
    full: Receiver<Buffer>,
    empty: SyncSender<Buffer>,
) -> std::io::Result<(File, u64)> {
    let mut direct = set_direct(&file, true).is_ok();
    let mut offset = 0u64;
    for buf in full {
        let result = file.write_all(buf.data());
        match result {
            Err(e) if direct && e.raw_os_error() == Some(libc::EINVAL) => {
                // The file system took the flag but refuses the write: rewrite the buffer
                // (possibly in part already written, with the same bytes) through the cache.
                direct = false;
                set_direct(&file, false)?;
                file.seek(SeekFrom::Start(offset))?;
                file.write_all(buf.data())?;
            }
            r => r?,
        }
        if !direct {
            start_writeback(&file, offset, STAGE as u64);
        }
        offset += STAGE as u64;
        // The filling side may have finished and gone; the buffer is then not needed.
        let _ = empty.send(buf);
    }
    Ok((file, offset))
}

/// Turns direct I/O on or off for `file` (Linux `O_DIRECT` through `fcntl`). Fails where
/// the file system refuses it, and off Linux when asked to turn it on.
fn set_direct(file: &File, on: bool) -> std::io::Result<()> {
    #[cfg(target_os = "linux")]
    {
        use std::os::fd::AsRawFd;
        let fd = file.as_raw_fd();
        // SAFETY: `fcntl` on the open file's descriptor; it reads no memory of ours.
        let flags = unsafe { libc::fcntl(fd, libc::F_GETFL) };
        if flags < 0 {
            return Err(std::io::Error::last_os_error());
        }
        let wanted = if on {
            flags | libc::O_DIRECT
        } else {
            flags & !libc::O_DIRECT
        };
        if wanted != flags {
            // SAFETY: as above.
            if unsafe { libc::fcntl(fd, libc::F_SETFL, wanted) } < 0 {
                return Err(std::io::Error::last_os_error());
            }
        }
        Ok(())
    }
    #[cfg(not(target_os = "linux"))]
    {
        let _ = file;
        if on {
            Err(std::io::Error::other("direct I/O is used on Linux only"))
        } else {
            Ok(())
        }
    }
}

/// Asks the kernel to start writing `len` bytes at `offset` of `file` to disk without
/// waiting (Linux `sync_file_range`). A hint only: an error shows at the closing `fsync`.
fn start_writeback(file: &File, offset: u64, len: u64) {
    #[cfg(target_os = "linux")]
    {
        use std::os::fd::AsRawFd;
        // SAFETY: the descriptor is the open file's; the call reads no memory.
        unsafe {
            libc::sync_file_range(
                file.as_raw_fd(),
                offset as libc::off64_t,
                len as libc::off64_t,
                libc::SYNC_FILE_RANGE_WRITE,
            );
        }
    }
    #[cfg(not(target_os = "linux"))]
    let _ = (file, offset, len);
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Read;

    /// Writes `data` through a [`Staged`] file at `path` in pieces of `piece` bytes and
    /// reads the file back.
    fn round_trip(path: &std::path::Path, data: &[u8], piece: usize) -> Vec<u8> {
        let mut staged = Staged::new(File::create(path).unwrap());
        for chunk in data.chunks(piece.max(1)) {
            staged.write_all(chunk).unwrap();
        }
        staged.finish().unwrap().sync_all().unwrap();
        let mut back = Vec::new();
        File::open(path).unwrap().read_to_end(&mut back).unwrap();
        back
    }

    fn pattern(n: usize) -> Vec<u8> {
        (0..n).map(|i| (i * 7 % 251) as u8).collect()
    }

    /// Every length around the buffer boundaries comes back byte for byte: no buffer,
    /// a tail only, exactly full buffers (no tail), and buffers plus a tail.
    #[test]
    fn lengths_around_buffer_boundaries_round_trip() {
        let tmp = tempfile::tempdir().unwrap();
        for n in [
            0,
            1,
            STAGE - 1,
            STAGE,
            STAGE + 1,
            2 * STAGE,
            3 * STAGE + 777,
        ] {
            let data = pattern(n);
            let p = tmp.path().join(format!("f{n}"));
            assert_eq!(round_trip(&p, &data, 65_537), data, "length {n}");
        }
    }

    /// A buffer starts at an aligned address and keeps it when filled to the brim (direct
    /// I/O refuses unaligned buffers), and holds exactly what was given to it.
    #[test]
    fn buffer_is_aligned_and_never_moves() {
        let mut b = Buffer::new();
        let at = b.data().as_ptr();
        assert_eq!(at as usize % ALIGN, 0);
        let data = pattern(STAGE + 10);
        assert_eq!(b.fill(&data[..100]), 100);
        assert_eq!(b.fill(&data[100..]), STAGE - 100);
        assert_eq!(b.data(), &data[..STAGE]);
        assert_eq!(b.data().as_ptr(), at);
        b.clear();
        assert_eq!(b.len(), 0);
        assert_eq!(b.fill(&data[..7]), 7);
        assert_eq!(b.data().as_ptr(), at);
    }

    /// A file system that may refuse direct I/O (tmpfs) gets the same bytes.
    #[test]
    fn memory_file_system_gets_the_same_bytes() {
        let shm = std::path::Path::new("/dev/shm");
        if !shm.is_dir() {
            return;
        }
        let tmp = tempfile::tempdir_in(shm).unwrap();
        let data = pattern(2 * STAGE + 4321);
        assert_eq!(round_trip(&tmp.path().join("f"), &data, 1 << 20), data);
    }

    /// A device that refuses every write (a full disk) gives an error, not a hang or a
    /// panic, whether the writer thread or the tail meets it.
    #[test]
    fn full_device_is_an_error() {
        let Ok(file) = std::fs::OpenOptions::new().write(true).open("/dev/full") else {
            return;
        };
        let mut staged = Staged::new(file);
        let data = pattern(3 * STAGE + 10);
        let written = data.chunks(1 << 20).try_for_each(|c| staged.write_all(c));
        if written.is_err() {
            // Writing on after the failure is an error again, not a panic.
            assert!(staged.write_all(&data[..STAGE]).is_err());
            assert!(staged.finish().is_err());
        } else {
            assert!(staged.finish().is_err(), "writing to /dev/full succeeded");
        }
    }
}
