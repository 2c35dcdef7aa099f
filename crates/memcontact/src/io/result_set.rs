//! Atomic result sets. A run's files are written into a staging directory beside the
//! target and moved into place in one step when all are complete, so the target holds
//! either the complete previous result or the complete new one, never a mix: a run killed
//! while writing, a full disk, or two runs into one directory cannot leave half of each.
//!
//! On Linux the new directory is swapped with the old one atomically (`renameat2` with
//! `RENAME_EXCHANGE`); the old one is then removed. Staging directories left by killed
//! runs are removed by the next run into the same place.

use crate::error::{Error, Result};
use std::ffi::OsString;
use std::path::{Path, PathBuf};

/// The marker in staging directory names: `.NAME.memcontact-staging-PID-NANOS`.
const STAGING: &str = ".memcontact-staging-";

/// A result set being written: files go into [`ResultSet::dir`], then [`ResultSet::commit`]
/// moves them into place. Dropping it uncommitted removes the staging directory.
#[derive(Debug)]
pub struct ResultSet {
    target: PathBuf,
    staging: PathBuf,
    committed: bool,
}

/// What may be at the target of a result set.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Existing {
    /// Nothing: the set will be created.
    Nothing,
    /// An empty directory.
    Empty,
    /// A previous result (it holds a `summary.json` or a `convergence.csv`): replaced as a
    /// whole.
    Result,
    /// A directory with other files: replaced only when forced.
    Other,
}

/// The file names that mark a directory as a memcontact result.
const MARKERS: [&str; 5] = [
    "summary.json",
    "manifest.json",
    "convergence.csv",
    "sweep.csv",
    "h_sweep.csv",
];

/// A temporary file of the per-file atomic writes of earlier versions, `.NAME.tmpPID`,
/// left in a result directory by a killed run: it does not make the directory foreign,
/// and it goes with the directory when a new set replaces it.
fn is_legacy_temporary(name: &str) -> bool {
    name.strip_prefix('.')
        .and_then(|rest| rest.rsplit_once(".tmp"))
        .is_some_and(|(base, pid)| {
            !base.is_empty() && !pid.is_empty() && pid.bytes().all(|b| b.is_ascii_digit())
        })
}

/// What is at `target` now.
pub fn existing(target: &Path) -> Result<Existing> {
    let io = |source| Error::Io {
        path: target.to_path_buf(),
        source,
    };
    match std::fs::symlink_metadata(target) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Existing::Nothing),
        Err(e) => return Err(io(e)),
        Ok(m) if !m.is_dir() => {
            return Err(Error::File {
                path: target.to_path_buf(),
                message: "exists and is not a directory: choose another output directory".into(),
            })
        }
        Ok(_) => {}
    }
    let mut any = false;
    for entry in std::fs::read_dir(target).map_err(io)? {
        let name = entry.map_err(io)?.file_name();
        let name = name.to_string_lossy();
        if MARKERS.contains(&name.as_ref()) {
            return Ok(Existing::Result);
        }
        any |= !is_legacy_temporary(&name);
    }
    Ok(if any {
        Existing::Other
    } else {
        Existing::Empty
    })
}

impl ResultSet {
    /// Starts a result set for directory `target`: checks what is there (another
    /// directory's contents are refused unless `force`), removes staging directories of
    /// runs that are gone, and creates a fresh staging directory.
    pub fn begin(target: &Path, force: bool) -> Result<ResultSet> {
        let name = target
            .file_name()
            .filter(|n| *n != "." && *n != "..")
            .ok_or_else(|| Error::File {
                path: target.to_path_buf(),
                message: "is not a directory name this run can replace: give a dedicated \
                          output directory, e.g. -o out"
                    .into(),
            })?;
        let cwd = std::env::current_dir().ok();
        if let (Some(cwd), Ok(t)) = (cwd, std::fs::canonicalize(target)) {
            if cwd.starts_with(&t) {
                return Err(Error::File {
                    path: target.to_path_buf(),
                    message: "contains the current directory: give a dedicated output \
                              directory, e.g. -o out"
                        .into(),
                });
            }
        }
        if existing(target)? == Existing::Other && !force {
            return Err(Error::File {
                path: target.to_path_buf(),
                message: "holds files that are not a memcontact result: choose another \
                          output directory, or pass --force to replace it as a whole"
                    .into(),
            });
        }
        let parent = parent_of(target);
        std::fs::create_dir_all(&parent).map_err(|source| Error::Io {
            path: parent.clone(),
            source,
        })?;
        clean_stale(&parent, name);
        let nanos = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map(|d| d.as_nanos())
            .unwrap_or(0);
        let mut staging_name = OsString::from(".");
        staging_name.push(name);
        staging_name.push(format!("{STAGING}{}-{nanos}", std::process::id()));
        let staging = parent.join(staging_name);
        std::fs::create_dir(&staging).map_err(|source| Error::Io {
            path: staging.clone(),
            source,
        })?;
        Ok(ResultSet {
            target: target.to_path_buf(),
            staging,
            committed: false,
        })
    }

    /// The staging directory: write the set's files here.
    pub fn dir(&self) -> &Path {
        &self.staging
    }

    /// Flushes the staged files to disk and moves the set into place in one step,
    /// replacing what was there as a whole.
    pub fn commit(mut self) -> Result<()> {
        let io = |path: &Path| {
            let path = path.to_path_buf();
            move |source| Error::Io { path, source }
        };
        sync_dir_files(&self.staging).map_err(io(&self.staging))?;
        let mut tries = 0;
        loop {
            tries += 1;
            match std::fs::rename(&self.staging, &self.target) {
                Ok(()) => break,
                Err(e) if is_occupied(&e) && tries < 8 => {
                    match exchange(&self.staging, &self.target) {
                        // The old set is now at the staging path.
                        Ok(()) => {
                            let _ = std::fs::remove_dir_all(&self.staging);
                            break;
                        }
                        // The target vanished in between (another run): rename again.
                        Err(e) if e.kind() == std::io::ErrorKind::NotFound => continue,
                        Err(e) if e.raw_os_error() == Some(libc_einval()) => {
                            // No atomic exchange here: move the old set aside first.
                            let aside = self.staging.with_extension("old");
                            std::fs::rename(&self.target, &aside).map_err(io(&self.target))?;
                            std::fs::rename(&self.staging, &self.target)
                                .map_err(io(&self.target))?;
                            let _ = std::fs::remove_dir_all(&aside);
                            break;
                        }
                        Err(e) => return Err(io(&self.target)(e)),
                    }
                }
                Err(e) => return Err(io(&self.target)(e)),
            }
        }
        if let Ok(d) = std::fs::File::open(parent_of(&self.target)) {
            let _ = d.sync_all();
        }
        self.committed = true;
        Ok(())
    }
}

impl Drop for ResultSet {
    fn drop(&mut self) {
        if !self.committed {
            let _ = std::fs::remove_dir_all(&self.staging);
        }
    }
}

/// The directory holding `target`.
fn parent_of(target: &Path) -> PathBuf {
    match target.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// `true` when a rename failed because the target directory exists and is not empty.
fn is_occupied(e: &std::io::Error) -> bool {
    matches!(
        e.kind(),
        std::io::ErrorKind::DirectoryNotEmpty | std::io::ErrorKind::AlreadyExists
    ) || e.raw_os_error() == Some(39)
        || e.raw_os_error() == Some(17)
}

fn libc_einval() -> i32 {
    22
}

/// Swaps two directories atomically.
#[cfg(target_os = "linux")]
fn exchange(a: &Path, b: &Path) -> std::io::Result<()> {
    use std::ffi::CString;
    use std::os::unix::ffi::OsStrExt;
    let ca = CString::new(a.as_os_str().as_bytes())?;
    let cb = CString::new(b.as_os_str().as_bytes())?;
    // SAFETY: both paths are valid NUL-terminated strings; renameat2 does not keep them.
    let r = unsafe {
        libc::renameat2(
            libc::AT_FDCWD,
            ca.as_ptr(),
            libc::AT_FDCWD,
            cb.as_ptr(),
            libc::RENAME_EXCHANGE,
        )
    };
    if r == 0 {
        Ok(())
    } else {
        Err(std::io::Error::last_os_error())
    }
}

/// No atomic exchange off Linux: the caller moves the old set aside.
#[cfg(not(target_os = "linux"))]
fn exchange(_a: &Path, _b: &Path) -> std::io::Result<()> {
    Err(std::io::Error::from_raw_os_error(libc_einval()))
}

/// Flushes every file of `dir` to disk.
fn sync_dir_files(dir: &Path) -> std::io::Result<()> {
    for entry in std::fs::read_dir(dir)? {
        let entry = entry?;
        if entry.file_type()?.is_file() {
            std::fs::File::open(entry.path())?.sync_all()?;
        }
    }
    std::fs::File::open(dir)?.sync_all()
}

/// Removes the staging directories (and their `.old` leftovers) of runs into `name` whose
/// process is gone.
fn clean_stale(parent: &Path, name: &std::ffi::OsStr) {
    let mut prefix = OsString::from(".");
    prefix.push(name);
    prefix.push(STAGING);
    let prefix = prefix.to_string_lossy().into_owned();
    let Ok(entries) = std::fs::read_dir(parent) else {
        return;
    };
    for entry in entries.flatten() {
        let file_name = entry.file_name().to_string_lossy().into_owned();
        let Some(rest) = file_name.strip_prefix(&prefix) else {
            continue;
        };
        let pid = rest.split('-').next().and_then(|p| p.parse::<u32>().ok());
        if pid.is_some_and(|p| p != std::process::id() && !process_alive(p)) {
            let _ = std::fs::remove_dir_all(entry.path());
        }
    }
}

/// Whether process `pid` exists (always `true` where this cannot be told).
fn process_alive(pid: u32) -> bool {
    if cfg!(target_os = "linux") {
        Path::new("/proc").join(pid.to_string()).exists()
    } else {
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(dir: &Path, name: &str, text: &str) {
        std::fs::write(dir.join(name), text).unwrap();
    }

    #[test]
    fn a_set_replaces_the_previous_one_as_a_whole() {
        let root = tempfile::tempdir().unwrap();
        let out = root.path().join("out");
        let set = ResultSet::begin(&out, false).unwrap();
        write(set.dir(), "summary.json", "1");
        write(set.dir(), "extra.png", "first");
        set.commit().unwrap();
        assert_eq!(
            std::fs::read_to_string(out.join("summary.json")).unwrap(),
            "1"
        );
        let set = ResultSet::begin(&out, false).unwrap();
        write(set.dir(), "summary.json", "2");
        set.commit().unwrap();
        assert_eq!(
            std::fs::read_to_string(out.join("summary.json")).unwrap(),
            "2"
        );
        // The second set had no picture: none survives from the first.
        assert!(!out.join("extra.png").exists());
        // Nothing but `out` is left beside it.
        let names: Vec<_> = std::fs::read_dir(root.path()).unwrap().collect();
        assert_eq!(names.len(), 1);
    }

    #[test]
    fn an_uncommitted_set_changes_nothing() {
        let root = tempfile::tempdir().unwrap();
        let out = root.path().join("out");
        let set = ResultSet::begin(&out, false).unwrap();
        write(set.dir(), "summary.json", "1");
        drop(set);
        assert!(!out.exists());
        assert_eq!(std::fs::read_dir(root.path()).unwrap().count(), 0);
    }

    #[test]
    fn a_foreign_directory_is_refused_unless_forced() {
        let root = tempfile::tempdir().unwrap();
        let out = root.path().join("mine");
        std::fs::create_dir(&out).unwrap();
        write(&out, "notes.txt", "keep me");
        let e = ResultSet::begin(&out, false).unwrap_err();
        assert!(e.to_string().contains("--force"), "{e}");
        assert!(out.join("notes.txt").exists());
        let set = ResultSet::begin(&out, true).unwrap();
        write(set.dir(), "summary.json", "1");
        set.commit().unwrap();
        assert!(!out.join("notes.txt").exists());
    }

    #[test]
    fn legacy_temporary_files_are_not_foreign_and_are_removed() {
        assert!(is_legacy_temporary(".solution.vtu.tmp1234"));
        assert!(!is_legacy_temporary("solution.vtu.tmp1234"));
        assert!(!is_legacy_temporary(".solution.vtu.tmp"));
        assert!(!is_legacy_temporary(".a.tmpx1"));
        let root = tempfile::tempdir().unwrap();
        let out = root.path().join("out");
        std::fs::create_dir(&out).unwrap();
        write(&out, ".solution.vtu.tmp4242", "half of an old write");
        assert_eq!(existing(&out).unwrap(), Existing::Empty);
        let set = ResultSet::begin(&out, false).unwrap();
        write(set.dir(), "summary.json", "1");
        set.commit().unwrap();
        let names: Vec<_> = std::fs::read_dir(&out)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names, ["summary.json"]);
    }

    #[test]
    fn stale_staging_of_a_dead_run_is_removed() {
        let root = tempfile::tempdir().unwrap();
        let out = root.path().join("out");
        // A pid that cannot exist (above the kernel's limit).
        let stale = root.path().join(format!(".out{STAGING}{}-1", u32::MAX - 1));
        std::fs::create_dir(&stale).unwrap();
        write(&stale, "solution.vtu", "half");
        let set = ResultSet::begin(&out, false).unwrap();
        assert!(!stale.exists());
        write(set.dir(), "summary.json", "1");
        set.commit().unwrap();
        assert_eq!(std::fs::read_dir(root.path()).unwrap().count(), 1);
    }
}
