//! The result set of a sweep or of load cases: a directory per step, `sweep.csv` and the
//! manifest.

use super::manifest::write_manifest;
use super::result::{new_run_id, write_files, WriteOptions};
use crate::case::{Case, StepSpec};
use crate::error::{Error, Result};
use crate::io::result_set::ResultSet;
use crate::outcome::sweep::StepRow;
use crate::outcome::{NodalFields, Outcome, Summary};
use std::path::Path;

/// The label of a step's results (`summary.json`'s `case`, the pictures' titles):
/// `label [step-003]` or `label [name of the load case]`.
pub fn step_label(label: &str, step: &StepSpec) -> String {
    format!("{label} [{}]", step.name)
}

/// The result set of a sweep or of load cases, written as one atomic result set: a
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
    /// Starts the set for directory `target`: checks what is there (another directory's
    /// contents are refused unless `force`), removes staging directories of runs that are
    /// gone, and creates a fresh staging directory.
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
            cell_data: Vec::new(),
            adapt: None,
            unconverged: false,
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
