//! The result set of an adaptive run: the final step's files (with the estimator per
//! triangle in `solution.vtu`), `adapt.csv` (one row per step), the caller's pictures, the
//! adaptive totals in `summary.json`, and, with `[output] keep_steps`, every step's result
//! set in `step-000/`, `step-001/`, ...

use super::row::AdaptRow;
use crate::case::Case;
use crate::error::Result;
use crate::io::result_set::ResultSet;
use crate::outcome::summary::AdaptTotals;
use crate::outcome::{NodalFields, Outcome, Summary};
use crate::write::{new_run_id, write_files, WriteOptions};
use std::path::Path;

/// The name of the table of steps.
pub const ADAPT_CSV: &str = "adapt.csv";

/// Writes `adapt.csv`: the header [`AdaptRow::HEADER`], one row per step, numbers at full
/// round-trip precision.
pub fn write_adapt_csv(path: &Path, rows: &[AdaptRow]) -> Result<()> {
    let mut text = AdaptRow::HEADER.join(",");
    text.push('\n');
    for r in rows {
        let cells = [
            r.step.to_string(),
            r.vertices.to_string(),
            r.unknowns.to_string(),
            format!("{:e}", r.estimator),
            format!("{:e}", r.energy),
            format!("{:e}", r.contact_area),
            r.iterations.to_string(),
            format!("{:e}", r.kkt_residual),
            format!("{:e}", r.seconds),
        ];
        text.push_str(&cells.join(","));
        text.push('\n');
    }
    crate::io::write_atomic(path, |w| w.write_all(text.as_bytes())).map(|_| ())
}

/// What the final result set of an adaptive run records besides its last step: the rows
/// of `adapt.csv`, η_T² of the last step (per triangle, user order) and the totals for
/// `summary.json`.
#[derive(Debug, Clone, Copy)]
pub struct AdaptHistory<'a> {
    /// One row per step solved.
    pub rows: &'a [AdaptRow],
    /// η_T² of the last step kept.
    pub indicators: &'a [f64],
    /// The totals of the loop.
    pub totals: &'a AdaptTotals,
}

/// An adaptive run's result set being written (nothing is in place until
/// [`AdaptSet::finish`]; dropping it leaves the target as it was).
#[derive(Debug)]
pub struct AdaptSet {
    set: ResultSet,
    run_id: String,
}

impl AdaptSet {
    /// Starts the set for directory `target`: checks what is there (another directory's
    /// contents are refused unless `force`), removes staging directories of runs that are
    /// gone, and creates a fresh staging directory.
    pub fn begin(target: &Path, force: bool) -> Result<AdaptSet> {
        Ok(AdaptSet {
            set: ResultSet::begin(target, force)?,
            run_id: new_run_id(),
        })
    }

    /// Writes step `row.step`'s result set into `step-NNN/` (for `[output] keep_steps`):
    /// its files, with its estimator per triangle (`eta2`, user order), and `extra`'s.
    pub fn write_step(
        &mut self,
        case: &Case,
        row: &AdaptRow,
        outcome: &Outcome,
        eta2: &[f64],
        options: &WriteOptions,
        extra: &mut dyn FnMut(&Path, &NodalFields) -> Result<Vec<String>>,
    ) -> Result<Summary> {
        let dir = self.set.dir().join(format!("step-{:03}", row.step));
        std::fs::create_dir_all(&dir).map_err(|source| crate::error::Error::Io {
            path: dir.clone(),
            source,
        })?;
        let options = WriteOptions {
            run_id: Some(self.run_id.clone()),
            cell_data: vec![("estimator".into(), eta2.iter().map(|e| e.sqrt()).collect())],
            ..options.clone()
        };
        write_files(&dir, outcome, case, &options, extra)
    }

    /// Writes the final step's files at the top of the set (`solution.vtu` with the
    /// estimator per triangle, `nodes.csv`, `extra`'s pictures, `adapt.csv`, and
    /// `summary.json` with the adaptive totals) for the last step `outcome`, and moves the
    /// set into place.
    pub fn finish(
        self,
        case: &Case,
        outcome: &Outcome,
        history: AdaptHistory<'_>,
        options: &WriteOptions,
        extra: &mut dyn FnMut(&Path, &NodalFields) -> Result<Vec<String>>,
    ) -> Result<Summary> {
        let options = WriteOptions {
            run_id: Some(self.run_id.clone()),
            cell_data: vec![(
                "estimator".into(),
                history.indicators.iter().map(|e| e.sqrt()).collect(),
            )],
            adapt: Some(history.totals.clone()),
            unconverged: false,
            ..options.clone()
        };
        let summary = write_files(self.set.dir(), outcome, case, &options, &mut |dir, f| {
            write_adapt_csv(&dir.join(ADAPT_CSV), history.rows)?;
            let mut names = extra(dir, f)?;
            names.push(ADAPT_CSV.to_string());
            Ok(names)
        })?;
        case.settings.cancel.check()?;
        self.set.commit()?;
        Ok(summary)
    }
}
