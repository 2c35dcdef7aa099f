//! The result files of a run, written as one atomic result set (written beside
//! the target and moved into place in one step, so it never holds half of two runs):
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

mod manifest;
mod pictures;
mod redraw;
mod result;
mod sensitivity;
mod study;
mod sweep;
#[cfg(test)]
mod tests;

pub use manifest::{write_manifest, Manifest, MANIFEST};
pub use memcontact_plot::{PlotKind, PlotOptions, Units as PlotUnits};
#[cfg(feature = "bench")]
pub use pictures::write_parts_seconds;
pub use pictures::{
    adapt_pictures, draw_all, outcome_pictures, pictures, plot_options, render_png, steps_kind,
    study_pictures, sweep_picture, write_png, write_result, SweepWriter, CONVERGENCE_PICTURE,
    H_SWEEP_PICTURE, MESH_PICTURE, SWEEP_PICTURE,
};
pub use redraw::{load as load_result, Loaded, LowerData, ResultData};
pub use result::{
    file_record, input_hash, new_run_id, write_fields, write_files, write_result_set, WriteOptions,
    LOWER_FIELDS, NODAL_FIELDS,
};
pub use sensitivity::{
    fit_picture, write_fit_csv, write_fit_json, write_sensitivity_csv, write_sensitivity_result,
    FIT_CSV, FIT_JSON, FIT_PICTURE, SENSITIVITY_COLUMNS, SENSITIVITY_CSV,
};
pub use study::{
    convergence_columns, h_sweep_columns, write_study, write_study_csv, StudyColumn,
    CONVERGENCE_COLUMNS, H_SWEEP_COLUMNS,
};
pub use sweep::{step_label, write_sweep_csv, SweepSet};
