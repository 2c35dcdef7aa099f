//! The result files of a run, written as one atomic result set ([`ResultSet`]):
//! `solution.vtu` (ParaView), `nodes.csv` (one row per vertex), any extra files of the
//! caller (pictures), and `summary.json` (the [`Summary`], with the run id, the input's hash
//! and the size and hash of every other file, so a mixed directory is detectable). A sweep
//! or a set of load cases is one [`SweepSet`]: a directory per step and `sweep.csv`.
//!
//! Every file of a set carries the set's run id: `summary.json` (or `manifest.json` for a
//! sweep or a convergence study, [`write_manifest`]) records it, `solution.vtu` holds it in
//! its `FieldData` array `run_id`, and the CSV files and pictures, whose formats have no
//! room for it (the CSV header lines are contracts), are bound to it by their hashes in
//! the summary or manifest.

use crate::io::csv::write_columns_csv;
use crate::io::json::write_json;
use crate::io::result_set::ResultSet;
use crate::io::vtu::{write_vtu_with_field_data, DataArray, VtuEncoding};
use crate::problem::{Case, VtuFormat};
use crate::results::NodalFields;
use crate::run::Outcome;
use crate::summary::{FileRecord, Summary};
use crate::sweep::{StepRow, StepSpec};
use crate::{Error, Result};
use std::path::Path;
use std::time::Instant;

/// The names of the per-vertex columns of `nodes.csv` (after `x`, `y`) and point fields of
/// `solution.vtu`, in order.
pub const NODAL_FIELDS: [&str; 6] = [
    "u",
    "phi",
    "penetration",
    "pressure",
    "contact_force",
    "state",
];

/// The columns of `nodes.csv` (and point fields of `solution.vtu`) a body below adds, after
/// [`NODAL_FIELDS`].
pub const LOWER_FIELDS: [&str; 5] = [
    "phi_low",
    "penetration_low",
    "pressure_low",
    "contact_force_low",
    "state_low",
];

/// How a result set is written.
#[derive(Debug, Clone)]
pub struct WriteOptions {
    /// The case's label in `summary.json` (its file path, or a name).
    pub label: String,
    /// The encoding of `solution.vtu`.
    pub vtu: VtuFormat,
    /// Write `nodes.csv` (`[output] csv`).
    pub csv: bool,
    /// Replace a directory that holds files other than a memcontact result.
    pub force: bool,
    /// When the run started (for `time_total_s`).
    pub started: Instant,
    /// The options of the pictures, recorded in `summary.json` so they can be redrawn.
    pub plot_options: Option<serde_json::Value>,
    /// The run id the files carry (`None`: a fresh one, [`new_run_id`]); the steps of a
    /// sweep share their sweep's.
    pub run_id: Option<String>,
}

/// A fresh random run identifier (32 hex digits).
pub fn new_run_id() -> String {
    use std::hash::{BuildHasher, Hasher};
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_nanos())
        .unwrap_or(0);
    let mut parts = [0u64; 2];
    for (k, p) in parts.iter_mut().enumerate() {
        let mut h = std::collections::hash_map::RandomState::new().build_hasher();
        h.write_u128(nanos);
        h.write_u32(std::process::id());
        h.write_usize(k);
        *p = h.finish();
    }
    format!("{:016x}{:016x}", parts[0], parts[1])
}

/// The hash of a case: XXH3-64 of its canonical JSON and, for a mesh file, of the file's
/// bytes (16 hex digits), so that a changed mesh file under the same name is another input.
pub fn input_hash(case: &Case) -> String {
    let json = serde_json::to_string(case).unwrap_or_default();
    let mut h = xxhash_rust::xxh3::Xxh3::new();
    h.update(json.as_bytes());
    if let crate::problem::MeshSource::File(path) = &case.problem.mesh.source {
        // Streamed through the hash (the digest of the whole file's bytes), never held in
        // memory whole.
        use std::io::Read;
        let kind = crate::resources::MESH_FILE;
        let streamed = crate::resources::open_input(path, kind).and_then(|(file, _)| {
            let mut reader = file.take(kind.cap + 1);
            let mut buf = vec![0u8; 1 << 20];
            loop {
                match reader.read(&mut buf) {
                    Ok(0) => return Ok(()),
                    Ok(n) => h.update(&buf[..n]),
                    Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                    Err(e) => {
                        return Err(Error::Io {
                            path: path.clone(),
                            source: e,
                        })
                    }
                }
            }
        });
        if streamed.is_err() {
            h.update(b"(the mesh file could not be read)");
        }
    }
    format!("{:016x}", h.digest())
}

/// The size and hash of a written file (read in blocks: a result file of hundreds of MB
/// is never held in memory twice).
pub fn file_record(path: &Path) -> Result<FileRecord> {
    use std::io::Read;
    let io = |source| Error::Io {
        path: path.to_path_buf(),
        source,
    };
    let mut file = std::fs::File::open(path).map_err(io)?;
    let mut hasher = xxhash_rust::xxh3::Xxh3::new();
    let mut buf = vec![0u8; 1 << 20];
    let mut bytes = 0u64;
    loop {
        let n = match file.read(&mut buf) {
            Ok(0) => break,
            Ok(n) => n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(io(e)),
        };
        hasher.update(&buf[..n]);
        bytes += n as u64;
    }
    Ok(crate::io::Written {
        bytes,
        xxh3: hasher.digest(),
    }
    .into())
}

/// Writes `solution.vtu` (with `run_id` in its field data) and `nodes.csv` of `fields` on
/// the outcome's mesh into `dir`; returns their names and records, hashed as written.
pub fn write_fields(
    dir: &Path,
    outcome: &Outcome,
    fields: &NodalFields,
    vtu: VtuFormat,
    csv: bool,
    run_id: &str,
) -> Result<Vec<(String, FileRecord)>> {
    let mesh = outcome.mesh();
    let region: Vec<i32> = mesh.regions.iter().map(|&r| r as i32).collect();
    let state: Vec<i32> = fields.state.iter().map(|&s| s as i32).collect();
    let covered: Vec<i32> = fields.covered.iter().map(|&c| c as i32).collect();
    let point_data = [
        ("u", DataArray::F64(&fields.u)),
        ("phi", DataArray::F64(&fields.phi)),
        ("penetration", DataArray::F64(&fields.penetration)),
        ("pressure", DataArray::F64(&fields.pressure)),
        ("contact_force", DataArray::F64(&fields.contact_force)),
        ("state", DataArray::I32(&state)),
    ];
    // The body below's fields follow the paper's (SPEC §5), when there is one.
    let lower = fields.lower.as_ref();
    let state_low: Vec<i32> =
        lower.map_or(Vec::new(), |l| l.state.iter().map(|&s| s as i32).collect());
    let covered_low: Vec<i32> = lower.map_or(Vec::new(), |l| {
        l.covered.iter().map(|&c| c as i32).collect()
    });
    let lower_data: Vec<(&str, DataArray)> = match lower {
        Some(l) => vec![
            ("phi_low", DataArray::F64(&l.phi)),
            ("penetration_low", DataArray::F64(&l.penetration)),
            ("pressure_low", DataArray::F64(&l.pressure)),
            ("contact_force_low", DataArray::F64(&l.contact_force)),
            ("state_low", DataArray::I32(&state_low)),
        ],
        None => Vec::new(),
    };
    let mut vtu_points = point_data.to_vec();
    vtu_points.push(("covered", DataArray::I32(&covered)));
    vtu_points.extend(lower_data.iter().cloned());
    if lower.is_some() {
        vtu_points.push(("covered_low", DataArray::I32(&covered_low)));
    }
    let x: Vec<f64> = mesh.points.iter().map(|p| p[0]).collect();
    let y: Vec<f64> = mesh.points.iter().map(|p| p[1]).collect();
    let mut columns = vec![("x", DataArray::F64(&x)), ("y", DataArray::F64(&y))];
    columns.extend(point_data);
    columns.extend(lower_data);
    // The two files are written side by side: one thread's formatting overlaps the other's
    // writes.
    let (vtu_written, csv_written) = rayon::join(
        || {
            write_vtu_with_field_data(
                &dir.join("solution.vtu"),
                &mesh,
                &vtu_points,
                &[("region", DataArray::I32(&region))],
                match vtu {
                    VtuFormat::Binary => VtuEncoding::Binary,
                    VtuFormat::Ascii => VtuEncoding::Ascii,
                },
                &[("run_id", run_id)],
            )
        },
        || csv.then(|| write_columns_csv(&dir.join("nodes.csv"), &columns)),
    );
    let mut files = vec![("solution.vtu".to_string(), vtu_written?.into())];
    if let Some(written) = csv_written {
        files.push(("nodes.csv".to_string(), written?.into()));
    }
    Ok(files)
}

/// Writes the files of `outcome` into the directory `dir` (which must exist and is not
/// replaced: use [`write_result_set`] for an atomic set): `solution.vtu`, `nodes.csv`,
/// what `extra` writes (it returns the names of its files), and `summary.json` last.
/// Returns the summary written.
pub fn write_files(
    dir: &Path,
    outcome: &Outcome,
    case: &Case,
    options: &WriteOptions,
    extra: &mut dyn FnMut(&Path, &NodalFields) -> Result<Vec<String>>,
) -> Result<Summary> {
    let t0 = Instant::now();
    let (fields, totals) = outcome.checked_fields()?;
    let r = &outcome.report;
    crate::checks::check_solution(
        r.energy,
        r.certificate.kkt(),
        outcome.discretization.model.is_rigid(),
    )?;
    let run_id = options.run_id.clone().unwrap_or_else(new_run_id);
    // The input's hash reads the mesh file again: alongside the writing, not after it.
    let (written, hash) = rayon::join(
        || write_fields(dir, outcome, &fields, options.vtu, options.csv, &run_id),
        || input_hash(case),
    );
    let written = written?;
    let names = extra(dir, &fields)?;
    let mut summary = Summary::new(
        &options.label,
        outcome,
        &outcome.discretization.quality,
        &totals,
    );
    summary.run_id = run_id;
    summary.input_hash = hash;
    summary.plot_options = options.plot_options.clone();
    // The fields' files were hashed as they were written; the extra files (pictures) are
    // read back, side by side.
    let records: Vec<FileRecord> = {
        use rayon::prelude::*;
        names
            .par_iter()
            .map(|name| file_record(&dir.join(name)))
            .collect::<Result<_>>()?
    };
    summary.files.extend(written);
    summary.files.extend(names.into_iter().zip(records));
    summary.time_write_s = t0.elapsed().as_secs_f64();
    summary.time_total_s = options.started.elapsed().as_secs_f64();
    write_json(&dir.join("summary.json"), &summary)?;
    Ok(summary)
}

/// Writes the result set of `outcome` into `target` atomically ([`ResultSet`]): the files
/// of [`write_files`], moved into place together. Returns the summary written.
pub fn write_result_set(
    target: &Path,
    outcome: &Outcome,
    case: &Case,
    options: &WriteOptions,
    extra: &mut dyn FnMut(&Path, &NodalFields) -> Result<Vec<String>>,
) -> Result<Summary> {
    let set = ResultSet::begin(target, options.force)?;
    let summary = write_files(set.dir(), outcome, case, options, extra)?;
    set.commit()?;
    Ok(summary)
}

/// The label of a step's results (`summary.json`'s `case`, the pictures' titles):
/// `label [step-003]` or `label [name of the load case]`.
pub fn step_label(label: &str, step: &StepSpec) -> String {
    format!("{label} [{}]", step.name)
}

/// The result set of a sweep or of load cases, written as one atomic [`ResultSet`]: a
/// directory per step (`step-000`, … or the load case's name) holding that step's files
/// ([`write_files`]), then `sweep.csv` (one row per step) and whatever the caller adds
/// beside it (the force-deflection picture), and `manifest.json` last: every step's files
/// carry the set's one run id.
#[derive(Debug)]
pub struct SweepSet {
    set: ResultSet,
    steps: usize,
    run_id: String,
    /// `sweep` or `load cases`, and the case's hash, from the steps written.
    kind: &'static str,
    input_hash: String,
}

impl SweepSet {
    /// Starts the set for directory `target` (see [`ResultSet::begin`]).
    pub fn begin(target: &Path, force: bool) -> Result<SweepSet> {
        Ok(SweepSet {
            set: ResultSet::begin(target, force)?,
            steps: 0,
            run_id: new_run_id(),
            kind: "sweep",
            input_hash: String::new(),
        })
    }

    /// The run id every file of the set carries.
    pub fn run_id(&self) -> &str {
        &self.run_id
    }

    /// The staging directory.
    pub fn dir(&self) -> &Path {
        self.set.dir()
    }

    /// The directories written so far.
    pub fn steps_written(&self) -> usize {
        self.steps
    }

    /// Writes the files of `step` (solved as `outcome`) into its directory; `options.label`
    /// is the step's label ([`step_label`]). Returns the step's summary.
    pub fn write_step(
        &mut self,
        step: &StepSpec,
        outcome: &Outcome,
        case: &Case,
        options: &WriteOptions,
        extra: &mut dyn FnMut(&Path, &NodalFields) -> Result<Vec<String>>,
    ) -> Result<Summary> {
        let dir = self.set.dir().join(&step.name);
        std::fs::create_dir(&dir).map_err(|source| Error::Io {
            path: dir.clone(),
            source,
        })?;
        let options = WriteOptions {
            run_id: Some(self.run_id.clone()),
            ..options.clone()
        };
        let summary = write_files(&dir, outcome, case, &options, extra)?;
        self.kind = if case.sweep.is_some() {
            "sweep"
        } else {
            "load cases"
        };
        self.input_hash = summary.input_hash.clone();
        self.steps += 1;
        Ok(summary)
    }

    /// Writes `sweep.csv` of `rows` and what `extra` writes into the set's directory
    /// (it receives the directory and the rows), then `manifest.json`, and moves the set
    /// into place.
    pub fn commit(
        self,
        rows: &[StepRow],
        extra: &mut dyn FnMut(&Path, &[StepRow]) -> Result<()>,
    ) -> Result<()> {
        write_sweep_csv(&self.set.dir().join("sweep.csv"), rows)?;
        extra(self.set.dir(), rows)?;
        write_manifest(self.set.dir(), self.kind, &self.run_id, &self.input_hash)?;
        self.set.commit()
    }
}

/// Writes `sweep.csv`: one row per step, with the columns of [`StepRow::HEADER`].
pub fn write_sweep_csv(path: &Path, rows: &[StepRow]) -> Result<()> {
    let mut text = StepRow::HEADER.join(",");
    text.push('\n');
    for r in rows {
        // `{:e}` is the shortest representation that reads back exactly.
        let cells = [
            r.step.to_string(),
            r.name.clone(),
            format!("{:e}", r.value),
            format!("{:e}", r.max_deflection),
            format!("{:e}", r.contact_area),
            format!("{:e}", r.liftoff_area),
            format!("{:e}", r.total_contact_force),
            format!("{:e}", r.max_pressure),
            format!("{:e}", r.energy),
            r.iterations.to_string(),
            format!("{:e}", r.kkt_residual),
            format!("{:e}", r.seconds),
        ];
        text.push_str(&cells.join(","));
        text.push('\n');
    }
    crate::io::write_atomic(path, |w| w.write_all(text.as_bytes())).map(|_| ())
}

/// `manifest.json` of a sweep or a convergence study: the run id, the input's hash, and
/// the size and hash of every other file of the set (by path relative to the set, step
/// directories included), so that a directory mixing two runs is detectable.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Manifest {
    /// What wrote the set: `sweep`, `load cases`, `convergence` or `h sweep`.
    pub kind: String,
    /// The run id shared by the set's files.
    pub run_id: String,
    /// The hash of the case ([`input_hash`]).
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn input_hash_covers_the_case_and_the_whole_mesh_file() {
        let dir = std::env::temp_dir().join(format!("memcontact-hash-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        // Only hashed, never parsed: any bytes will do, over several read blocks.
        let mesh = dir.join("site.msh");
        let bytes: Vec<u8> = (0..3_000_001u32)
            .map(|i| (i.wrapping_mul(2_654_435_761) >> 24) as u8)
            .collect();
        std::fs::write(&mesh, &bytes).unwrap();
        let text = "[mesh]\nfile = \"site.msh\"\n[membrane]\ntension = 1.0\nload = 1.0\n\
                    [obstacle]\nshape = 0.1\nstiffness = 10.0\n";
        let case = Case::from_toml_str(text, Some(&dir.join("case.toml"))).unwrap();
        // The digest of the case's JSON followed by the file's bytes, all at once.
        let mut whole = serde_json::to_string(&case).unwrap().into_bytes();
        whole.extend_from_slice(&bytes);
        let expected = format!("{:016x}", xxhash_rust::xxh3::xxh3_64(&whole));
        assert_eq!(input_hash(&case), expected);
        // One byte of the mesh changed changes the hash.
        let mut changed = bytes.clone();
        let last = changed.len() - 2;
        changed[last] ^= 1;
        std::fs::write(&mesh, &changed).unwrap();
        assert_ne!(input_hash(&case), expected);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
