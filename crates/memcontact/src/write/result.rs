//! The result set of one solve: `solution.vtu`, `nodes.csv`, the caller's extra files and
//! `summary.json`, with the run id and the hashes that bind them.

use crate::case::{Case, VtuFormat};
use crate::error::{Error, Result};
use crate::io::csv::write_columns_csv;
use crate::io::json::write_json;
use crate::io::result_set::ResultSet;
use crate::io::vtu::{write_vtu_with_field_data, DataArray, VtuEncoding};
use crate::mesh::Mesh;
use crate::outcome::fields::NodalFields;
use crate::outcome::summary::{FileRecord, Summary};
use crate::outcome::Outcome;
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
    /// Replace a directory that holds files other than a memcontact result.
    pub force: bool,
    /// When the run started (for `time_total_s`).
    pub started: Instant,
    /// The options of the pictures, recorded in `summary.json` so they can be redrawn.
    pub plot_options: Option<serde_json::Value>,
    /// The run id the files carry (`None`: a fresh one, [`new_run_id`]); the steps of a
    /// sweep share their sweep's.
    pub run_id: Option<String>,
    /// Further cell data of `solution.vtu`, one value per triangle in the user's order
    /// (the adaptive loop's `estimator`).
    pub cell_data: Vec<(String, Vec<f64>)>,
    /// The adaptive loop's totals for `summary.json` (with `[adapt]`).
    pub adapt: Option<crate::outcome::summary::AdaptTotals>,
    /// Write the files of a solve the settings did not accept (marked `"accepted": false`
    /// in `summary.json`); otherwise [`crate::run::run_to_files`] writes nothing for it.
    pub unconverged: bool,
}

impl WriteOptions {
    /// The options of a result set labelled `label` (its name in `summary.json`): binary
    /// VTU, started now, a fresh run id, an existing result replaced but no other
    /// directory, nothing written for an outcome the settings did not accept.
    pub fn new(label: impl Into<String>) -> WriteOptions {
        WriteOptions {
            label: label.into(),
            vtu: VtuFormat::default(),
            force: false,
            started: Instant::now(),
            plot_options: None,
            run_id: None,
            cell_data: Vec::new(),
            adapt: None,
            unconverged: false,
        }
    }
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
        let kind = crate::io::input::MESH_FILE;
        let streamed = crate::io::input::open_input(path, kind).and_then(|(file, _)| {
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

/// Writes `solution.vtu` (with `run_id` in its field data) and, when `csv`, `nodes.csv` of
/// `fields` on the outcome's mesh into `dir`; returns their names and records, hashed as
/// written.
pub fn write_fields(
    dir: &Path,
    outcome: &Outcome,
    fields: &NodalFields,
    vtu: VtuFormat,
    csv: bool,
    run_id: &str,
    cell_data: &[(String, Vec<f64>)],
) -> Result<Vec<(String, FileRecord)>> {
    write_fields_with(dir, outcome, fields, vtu, csv, run_id, cell_data, &[])
}

/// [`write_fields`] with further point fields of `solution.vtu` (`extra_points`, one value
/// per vertex in the user's order: the sensitivity run's influence maps).
#[allow(clippy::too_many_arguments)]
pub(crate) fn write_fields_with(
    dir: &Path,
    outcome: &Outcome,
    fields: &NodalFields,
    vtu: VtuFormat,
    csv: bool,
    run_id: &str,
    cell_data: &[(String, Vec<f64>)],
    extra_points: &[(String, Vec<f64>)],
) -> Result<Vec<(String, FileRecord)>> {
    let mesh = outcome.mesh();
    // The two files are written side by side: one thread's formatting overlaps the other's
    // writes.
    let (vtu_written, csv_written) = rayon::join(
        || write_solution_vtu(dir, &mesh, fields, vtu, run_id, cell_data, extra_points),
        || csv.then(|| write_nodes_csv(dir, &mesh, fields)),
    );
    let mut files = vec![vtu_written?];
    if let Some(written) = csv_written {
        files.push(written?);
    }
    Ok(files)
}

/// The point fields of `solution.vtu` and the columns of `nodes.csv` after `x`, `y`
/// ([`NODAL_FIELDS`], then [`LOWER_FIELDS`] with a body below), as one call's integer
/// copies of the state fields let them be borrowed.
fn nodal_arrays<'a>(
    fields: &'a NodalFields,
    state: &'a [i32],
    state_low: &'a [i32],
) -> Vec<(&'static str, DataArray<'a>)> {
    let mut arrays = vec![
        ("u", DataArray::F64(&fields.u)),
        ("phi", DataArray::F64(&fields.phi)),
        ("penetration", DataArray::F64(&fields.penetration)),
        ("pressure", DataArray::F64(&fields.pressure)),
        ("contact_force", DataArray::F64(&fields.contact_force)),
        ("state", DataArray::I32(state)),
    ];
    // The body below's fields follow the paper's (docs/theory.md#second-body), when there
    // is one.
    if let Some(l) = &fields.lower {
        arrays.extend([
            ("phi_low", DataArray::F64(&l.phi)),
            ("penetration_low", DataArray::F64(&l.penetration)),
            ("pressure_low", DataArray::F64(&l.pressure)),
            ("contact_force_low", DataArray::F64(&l.contact_force)),
            ("state_low", DataArray::I32(state_low)),
        ]);
    }
    arrays
}

/// `values` as `i32`s (the VTU and CSV integer columns).
fn as_i32<T: Copy + Into<i32>>(values: &[T]) -> Vec<i32> {
    values.iter().map(|&v| v.into()).collect()
}

/// Writes `solution.vtu` of `fields` on `mesh` into `dir` (`run_id` in its field data,
/// `cell_data` after the regions), hashed as written; returns its name and record.
pub(super) fn write_solution_vtu(
    dir: &Path,
    mesh: &Mesh,
    fields: &NodalFields,
    vtu: VtuFormat,
    run_id: &str,
    cell_data: &[(String, Vec<f64>)],
    extra_points: &[(String, Vec<f64>)],
) -> Result<(String, FileRecord)> {
    let region: Vec<i32> = mesh.regions.iter().map(|&r| r as i32).collect();
    let state = as_i32(&fields.state);
    let covered = as_i32(&fields.covered);
    let lower = fields.lower.as_ref();
    let state_low = lower.map_or(Vec::new(), |l| as_i32(&l.state));
    let covered_low = lower.map_or(Vec::new(), |l| as_i32(&l.covered));
    // The obstacle's fields, `covered`, the body below's, `covered_low`.
    let mut points = nodal_arrays(fields, &state, &state_low);
    points.insert(NODAL_FIELDS.len(), ("covered", DataArray::I32(&covered)));
    if lower.is_some() {
        points.push(("covered_low", DataArray::I32(&covered_low)));
    }
    // A run's further fields (a sensitivity run's influence maps) last.
    points.extend(
        extra_points
            .iter()
            .map(|(n, v)| (n.as_str(), DataArray::F64(v))),
    );
    let cells: Vec<(&str, DataArray)> = std::iter::once(("region", DataArray::I32(&region)))
        .chain(
            cell_data
                .iter()
                .map(|(n, v)| (n.as_str(), DataArray::F64(v))),
        )
        .collect();
    let written = write_vtu_with_field_data(
        &dir.join("solution.vtu"),
        mesh,
        &points,
        &cells,
        match vtu {
            VtuFormat::Binary => VtuEncoding::Binary,
            VtuFormat::Ascii => VtuEncoding::Ascii,
            VtuFormat::Compressed => VtuEncoding::Compressed,
        },
        &[("run_id", run_id)],
    )?;
    Ok(("solution.vtu".to_string(), written.into()))
}

/// Writes `nodes.csv` of `fields` on `mesh` into `dir` (`x`, `y`, then the nodal
/// columns), hashed as written; returns its name and record.
pub(super) fn write_nodes_csv(
    dir: &Path,
    mesh: &Mesh,
    fields: &NodalFields,
) -> Result<(String, FileRecord)> {
    let state = as_i32(&fields.state);
    let state_low = fields
        .lower
        .as_ref()
        .map_or(Vec::new(), |l| as_i32(&l.state));
    let x: Vec<f64> = mesh.points.iter().map(|p| p[0]).collect();
    let y: Vec<f64> = mesh.points.iter().map(|p| p[1]).collect();
    let mut columns = vec![("x", DataArray::F64(&x)), ("y", DataArray::F64(&y))];
    columns.extend(nodal_arrays(fields, &state, &state_low));
    let written = write_columns_csv(&dir.join("nodes.csv"), &columns)?;
    Ok(("nodes.csv".to_string(), written.into()))
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
    write_files_with(dir, outcome, case, options, extra, &Extras::default())
}

/// What a run adds to the files of its solve: point fields of `solution.vtu` and keys of
/// `summary.json` (a sensitivity run's influence maps and totals).
#[derive(Debug, Clone, Default)]
pub(crate) struct Extras {
    /// Further point fields of `solution.vtu`, one value per vertex in the user's order.
    pub(crate) point_data: Vec<(String, Vec<f64>)>,
    /// The sensitivity totals of `summary.json`.
    pub(crate) sensitivity: Option<crate::outcome::SensitivityTotals>,
}

/// [`write_files`] with the [`Extras`] of a run.
pub(crate) fn write_files_with(
    dir: &Path,
    outcome: &Outcome,
    case: &Case,
    options: &WriteOptions,
    extra: &mut dyn FnMut(&Path, &NodalFields) -> Result<Vec<String>>,
    extras: &Extras,
) -> Result<Summary> {
    let t0 = Instant::now();
    let (fields, totals) = outcome.checked_fields()?;
    let r = &outcome.report;
    crate::solve::check_solution(
        r.energy,
        r.certificate.kkt(),
        outcome.discretization.model.is_rigid(),
    )?;
    let run_id = options.run_id.clone().unwrap_or_else(new_run_id);
    let mesh = outcome.mesh();
    let csv = case.output.writes_csv();
    // Everything at once: `solution.vtu`, `nodes.csv` and the input's hash (which reads
    // the mesh file again) on the pool's threads, the extra files (pictures, drawn on the
    // pool too) from this one, which need not be `Send`, then read back for their records.
    // No file's bytes depend on another's. The errors come in the order of a sequential
    // write: the fields' files first.
    let mut vtu_written = None;
    let mut csv_written = None;
    let mut hash = String::new();
    let extra_written = rayon::in_place_scope(|s| {
        s.spawn(|_| {
            vtu_written = Some(write_solution_vtu(
                dir,
                &mesh,
                &fields,
                options.vtu,
                &run_id,
                &options.cell_data,
                &extras.point_data,
            ))
        });
        if csv {
            s.spawn(|_| csv_written = Some(write_nodes_csv(dir, &mesh, &fields)));
        }
        s.spawn(|_| hash = input_hash(case));
        extra(dir, &fields).and_then(|names| {
            let records = names
                .iter()
                .map(|name| file_record(&dir.join(name)))
                .collect::<Result<Vec<FileRecord>>>()?;
            Ok(names.into_iter().zip(records))
        })
    });
    let mut written = vec![vtu_written.expect("the VTU task ran")?];
    if let Some(w) = csv_written {
        written.push(w?);
    }
    case.settings.cancel.check()?;
    let extra_written = extra_written?;
    let mut summary = Summary::new(
        &options.label,
        outcome,
        &outcome.discretization.quality,
        &totals,
    );
    summary.run_id = run_id;
    summary.input_hash = hash;
    summary.plot_options = options.plot_options.clone();
    summary.adapt = options.adapt.clone();
    summary.sensitivity = extras.sensitivity.clone();
    summary.files.extend(written);
    summary.files.extend(extra_written);
    summary.time_write_s = t0.elapsed().as_secs_f64();
    summary.time_total_s = options.started.elapsed().as_secs_f64();
    write_json(&dir.join("summary.json"), &summary)?;
    Ok(summary)
}

/// Writes the result set of `outcome` into `target` atomically: the files
/// of [`write_files`], written into a staging directory beside it and moved into place
/// together (the target holds the complete previous result or the complete new one). Returns the summary written.
pub fn write_result_set(
    target: &Path,
    outcome: &Outcome,
    case: &Case,
    options: &WriteOptions,
    extra: &mut dyn FnMut(&Path, &NodalFields) -> Result<Vec<String>>,
) -> Result<Summary> {
    write_result_set_with(target, outcome, case, options, extra, &Extras::default())
}

/// [`write_result_set`] with the [`Extras`] of a run.
pub(crate) fn write_result_set_with(
    target: &Path,
    outcome: &Outcome,
    case: &Case,
    options: &WriteOptions,
    extra: &mut dyn FnMut(&Path, &NodalFields) -> Result<Vec<String>>,
    extras: &Extras,
) -> Result<Summary> {
    let set = ResultSet::begin(target, options.force)?;
    let summary = write_files_with(set.dir(), outcome, case, options, extra, extras)?;
    // Stopped while writing: the staging directory goes, the previous result stays.
    case.settings.cancel.check()?;
    set.commit()?;
    Ok(summary)
}
