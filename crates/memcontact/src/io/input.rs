//! Input files, read with care: the one home of the size caps of case files and meshes.
//! Input files are opened only when they are regular files (a FIFO or a device such as
//! `/dev/zero` is refused before anything is read) and read with a size cap.

use crate::error::{Error, Result};
use std::io::Read;
use std::path::Path;

/// An input file kind: its size cap and how it is named in messages.
#[derive(Debug, Clone, Copy)]
pub struct InputKind {
    /// The largest size read, bytes.
    pub cap: u64,
    /// What the file must be, for messages (`"a case file (TOML text)"`).
    pub what: &'static str,
}

/// The largest case file read (bytes): a case is a few kilobytes of text.
pub const CASE_FILE_CAP: u64 = 16 << 20;

/// The largest mesh file read (bytes): 4 GiB holds a Gmsh mesh of about 50 million
/// triangles in ASCII, more in binary.
pub const MESH_FILE_CAP: u64 = 4 << 30;

/// A case file.
pub const CASE_FILE: InputKind = InputKind {
    cap: CASE_FILE_CAP,
    what: "a case file (TOML text)",
};

/// A Gmsh mesh file.
pub const MESH_FILE: InputKind = InputKind {
    cap: MESH_FILE_CAP,
    what: "a mesh file (Gmsh MSH)",
};

/// Reads an input file whole: it must be a regular file of at most `kind.cap` bytes.
/// The file is opened without blocking (a FIFO with no writer cannot hang the run) and
/// checked on the opened descriptor, then read with the cap (a file growing meanwhile is
/// still refused, not read without end).
pub fn read_input(path: &Path, kind: InputKind) -> Result<Vec<u8>> {
    let (file, size) = open_input(path, kind)?;
    let cannot = |e: std::io::Error| Error::File {
        path: path.to_path_buf(),
        message: format!("cannot read: {e}"),
    };
    #[cfg(unix)]
    if size >= PARALLEL_READ {
        if let Some(bytes) = read_in_parts(&file, size).map_err(cannot)? {
            return Ok(bytes);
        }
    }
    let mut bytes = Vec::with_capacity(size as usize);
    file.take(kind.cap + 1)
        .read_to_end(&mut bytes)
        .map_err(cannot)?;
    if bytes.len() as u64 > kind.cap {
        return Err(too_big(path, kind, bytes.len() as u64));
    }
    Ok(bytes)
}

/// Files from this size on are read by [`read_in_parts`].
#[cfg(unix)]
const PARALLEL_READ: u64 = 16 << 20;

/// The `size` bytes of a regular file read in one part per thread at once (copying a
/// large mesh out of the page cache, and the first touch of the buffer, are shared by the
/// cores). `None` when the file has grown since its size was taken: the caller then reads
/// it to its end with the cap.
#[cfg(unix)]
fn read_in_parts(file: &std::fs::File, size: u64) -> std::io::Result<Option<Vec<u8>>> {
    use rayon::prelude::*;
    use std::os::unix::fs::FileExt;
    let n = size as usize;
    let mut bytes = vec![0u8; n];
    let part = n.div_ceil(rayon::current_num_threads().max(1));
    bytes
        .par_chunks_mut(part)
        .enumerate()
        .try_for_each(|(k, chunk)| file.read_exact_at(chunk, (k * part) as u64))?;
    let mut probe = [0u8; 1];
    Ok((file.read_at(&mut probe, size)? == 0).then_some(bytes))
}

/// Opens an input file for reading as [`read_input`] does (a regular file of at most
/// `kind.cap` bytes, opened without blocking); returns it with its size. Readers must
/// stop at `kind.cap + 1` bytes, as [`read_input`] does.
pub fn open_input(path: &Path, kind: InputKind) -> Result<(std::fs::File, u64)> {
    let file_err = |message: String| Error::File {
        path: path.to_path_buf(),
        message,
    };
    let mut options = std::fs::OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        options.custom_flags(libc::O_NONBLOCK);
    }
    let file = options
        .open(path)
        .map_err(|e| file_err(format!("cannot read: {e}")))?;
    let meta = file
        .metadata()
        .map_err(|e| file_err(format!("cannot read: {e}")))?;
    if !meta.is_file() {
        return Err(file_err(format!(
            "is a {}, not a regular file: {} is needed",
            file_type_name(&meta),
            kind.what
        )));
    }
    if meta.len() > kind.cap {
        return Err(too_big(path, kind, meta.len()));
    }
    Ok((file, meta.len()))
}

/// The error for an input file of `size` bytes, more than `kind` allows.
fn too_big(path: &Path, kind: InputKind, size: u64) -> Error {
    Error::File {
        path: path.to_path_buf(),
        message: format!(
            "is {size} bytes, more than {} can be ({} bytes)",
            kind.what, kind.cap
        ),
    }
}

/// How a file that is not a regular file is named.
fn file_type_name(meta: &std::fs::Metadata) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        let t = meta.file_type();
        if t.is_fifo() {
            return "named pipe (FIFO)";
        }
        if t.is_char_device() || t.is_block_device() {
            return "device";
        }
        if t.is_socket() {
            return "socket";
        }
    }
    if meta.is_dir() {
        "directory"
    } else {
        "special file"
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn large_files_are_read_whole_in_parts() {
        // Above the size read in parallel parts, and not a multiple of the part size.
        let n = PARALLEL_READ as usize + 12_345;
        let bytes: Vec<u8> = (0..n as u64)
            .map(|i| (i.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 56) as u8)
            .collect();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("big.msh");
        std::fs::write(&path, &bytes).unwrap();
        for threads in [1, 2, 3] {
            let read =
                crate::parallel::on_threads(threads, || read_input(&path, MESH_FILE)).unwrap();
            assert!(read == bytes, "{threads} threads");
        }
        let e = read_input(&path, CASE_FILE).unwrap_err().to_string();
        assert!(e.contains("big.msh"), "{e}");
    }

    #[test]
    fn special_files_are_refused_without_blocking() {
        let dir = tempfile::tempdir().unwrap();
        let e = read_input(dir.path(), MESH_FILE).unwrap_err().to_string();
        assert!(
            e.contains("not a regular file") && e.contains("directory"),
            "{e}"
        );
        #[cfg(unix)]
        {
            let e = read_input(Path::new("/dev/zero"), CASE_FILE)
                .unwrap_err()
                .to_string();
            assert!(e.contains("device"), "{e}");
            let fifo = dir.path().join("pipe");
            let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
            // SAFETY: a valid NUL-terminated path.
            assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
            let e = read_input(&fifo, MESH_FILE).unwrap_err().to_string();
            assert!(e.contains("FIFO"), "{e}");
        }
        let big = dir.path().join("big");
        std::fs::write(&big, vec![b' '; 100]).unwrap();
        let small = InputKind {
            cap: 99,
            what: "a test file",
        };
        let e = read_input(&big, small).unwrap_err().to_string();
        assert!(e.contains("100 bytes") && e.contains("99 bytes"), "{e}");
        assert_eq!(read_input(&big, CASE_FILE).unwrap().len(), 100);
    }
}
