//! Readers and writers: Gmsh meshes in, VTU / CSV / JSON out. Plain functions over library types.

mod atomic;
pub(crate) mod csv;
mod direct_writer;
pub mod gmsh;
pub(crate) mod input;
pub(crate) mod json;
pub(crate) mod numbers;
pub(crate) mod result_set;
pub mod vtu;
pub use atomic::{write_atomic, Written};

/// A path in a fresh temporary directory that is removed with it (tests of the writers).
#[cfg(test)]
pub(crate) struct TmpPath {
    _dir: tempfile::TempDir,
    path: std::path::PathBuf,
}

#[cfg(test)]
impl TmpPath {
    /// `name` in a new temporary directory.
    pub(crate) fn new(name: &str) -> TmpPath {
        let dir = tempfile::tempdir().expect("a temporary directory");
        let path = dir.path().join(name);
        TmpPath { _dir: dir, path }
    }
}

#[cfg(test)]
impl std::ops::Deref for TmpPath {
    type Target = std::path::Path;
    fn deref(&self) -> &std::path::Path {
        &self.path
    }
}

#[cfg(test)]
impl AsRef<std::path::Path> for TmpPath {
    fn as_ref(&self) -> &std::path::Path {
        &self.path
    }
}
