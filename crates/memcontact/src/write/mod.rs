//! The result files of a run, written as one atomic result set ([`crate::io::result_set::ResultSet`]):
//! `solution.vtu` (ParaView), `nodes.csv` (one row per vertex), any extra files of the
//! caller (pictures), and `summary.json` (the [`crate::outcome::Summary`], with the run id, the input's hash
//! and the size and hash of every other file, so a mixed directory is detectable). A sweep
//! or a set of load cases is one [`SweepSet`]: a directory per step and `sweep.csv`.
//!
//! Every file of a set carries the set's run id: `summary.json` (or `manifest.json` for a
//! sweep or a convergence study, [`write_manifest`]) records it, `solution.vtu` holds it in
//! its `FieldData` array `run_id`, and the CSV files and pictures, whose formats have no
//! room for it (the CSV header lines are contracts), are bound to it by their hashes in
//! the summary or manifest.

mod adapt;
mod manifest;
mod result;
mod sensitivity;
mod study;
mod sweep;
#[cfg(test)]
mod tests;

pub use adapt::{write_adapt_csv, AdaptHistory, AdaptSet, ADAPT_CSV};
pub use manifest::{write_manifest, Manifest, MANIFEST};
pub use result::{
    file_record, input_hash, new_run_id, write_fields, write_fields_with, write_files,
    write_files_with, write_result_set, write_result_set_with, Extras, WriteOptions, LOWER_FIELDS,
    NODAL_FIELDS,
};
pub use sensitivity::{
    write_fit_csv, write_fit_json, write_sensitivity_csv, FIT_CSV, FIT_JSON, SENSITIVITY_COLUMNS,
    SENSITIVITY_CSV,
};
pub use study::{
    convergence_columns, h_sweep_columns, write_study, write_study_csv, StudyColumn,
    CONVERGENCE_COLUMNS, H_SWEEP_COLUMNS,
};
pub use sweep::{step_label, write_sweep_csv, SweepSet};
