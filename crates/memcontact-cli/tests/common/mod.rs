//! Helpers shared by the end-to-end tests: run the `memcontact` binary, read its output.

#![allow(dead_code)]

use std::path::{Path, PathBuf};

use std::process::{Command, Output};

/// The binary under test.
pub fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_memcontact"))
}

/// The repository's `examples/` folder.
pub fn examples() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples")
}

/// Runs the binary with `args`.
pub fn run(args: &[&str]) -> Output {
    bin().args(args).output().expect("the binary runs")
}

/// Standard output and standard error together.
pub fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

/// A fresh, empty temporary directory, removed when the value is dropped; it derefs to
/// its path.
pub struct Tmp(tempfile::TempDir);

impl std::ops::Deref for Tmp {
    type Target = Path;
    fn deref(&self) -> &Path {
        self.0.path()
    }
}

impl AsRef<Path> for Tmp {
    fn as_ref(&self) -> &Path {
        self.0.path()
    }
}

impl AsRef<std::ffi::OsStr> for Tmp {
    fn as_ref(&self) -> &std::ffi::OsStr {
        self.0.path().as_os_str()
    }
}

/// A fresh, empty temporary directory for test `name` of suite `suite` (removed when
/// dropped).
pub fn tmp_in(suite: &str, name: &str) -> Tmp {
    Tmp(tempfile::Builder::new()
        .prefix(&format!("memcontact-{suite}-{name}-"))
        .tempdir()
        .expect("a temporary directory"))
}
