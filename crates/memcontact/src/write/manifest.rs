//! `manifest.json`: the run id, the input's hash and the size and hash of every file of a
//! sweep's or a study's result set.

use super::result::file_record;
use crate::error::{Error, Result};
use crate::io::json::write_json;
use crate::outcome::summary::FileRecord;
use std::path::Path;

/// `manifest.json` of a sweep or a convergence study: the run id, the input's hash, and
/// the size and hash of every other file of the set (by path relative to the set, step
/// directories included), so that a directory mixing two runs is detectable.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Manifest {
    /// What wrote the set: `sweep`, `load cases`, `convergence` or `h sweep`.
    pub kind: String,
    /// The run id shared by the set's files.
    pub run_id: String,
    /// The hash of the case ([`super::input_hash`]).
    pub input_hash: String,
    /// Every other file of the set, by relative path (`/`-separated).
    pub files: std::collections::BTreeMap<String, FileRecord>,
}

/// Writes `manifest.json` into the result-set directory `dir`, listing every other regular
/// file under it. Returns the manifest written.
pub fn write_manifest(dir: &Path, kind: &str, run_id: &str, input_hash: &str) -> Result<Manifest> {
    let mut files = std::collections::BTreeMap::new();
    let mut pending = vec![(dir.to_path_buf(), String::new())];
    while let Some((d, prefix)) = pending.pop() {
        let io = |source| Error::Io {
            path: d.clone(),
            source,
        };
        for entry in std::fs::read_dir(&d).map_err(io)? {
            let entry = entry.map_err(io)?;
            let name = format!("{prefix}{}", entry.file_name().to_string_lossy());
            let kind = entry.file_type().map_err(io)?;
            if kind.is_dir() {
                pending.push((entry.path(), format!("{name}/")));
            } else if kind.is_file() && name != MANIFEST {
                files.insert(name, file_record(&entry.path())?);
            }
        }
    }
    let manifest = Manifest {
        kind: kind.to_string(),
        run_id: run_id.to_string(),
        input_hash: input_hash.to_string(),
        files,
    };
    write_json(&dir.join(MANIFEST), &manifest)?;
    Ok(manifest)
}

/// The file name of a [`Manifest`].
pub const MANIFEST: &str = "manifest.json";
