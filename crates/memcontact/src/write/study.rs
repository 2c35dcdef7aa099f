//! The result set of a convergence study: `convergence.csv` (one per variant when
//! comparing) or `h_sweep.csv`, the caller's pictures, and `manifest.json`, moved into place
//! together.

use super::manifest::{write_manifest, MANIFEST};
use super::result::{input_hash, new_run_id};
use crate::case::Case;
use crate::error::Result;
use crate::io::csv::write_columns_csv;
use crate::io::numbers::DataArray;
use crate::io::result_set::ResultSet;
use crate::verify::convergence::{LevelResult, RigidLimitRow, Study};
use crate::verify::study::{StudyOutcome, StudyResult};
use std::path::Path;

/// The columns of `convergence.csv`, in order: the required ones first, then the extras.
pub const CONVERGENCE_COLUMNS: [&str; 28] = [
    "level",
    "vertices",
    "l_n",
    "l2_error",
    "h1_error",
    "max_nodal_error",
    "l2_rate",
    "h1_rate",
    "triangles",
    "unknowns",
    "max_nodal_rate",
    "contact_area",
    "contact_radius",
    "contact_area_error",
    "contact_radius_error",
    "gap_area",
    "gap_l2",
    "gap_h1",
    "l2_increment",
    "h1_increment",
    "l2_increment_rate",
    "h1_increment_rate",
    "iterations",
    "kkt_residual",
    "assembly_s",
    "solve_s",
    "error_s",
    "epsilon",
];

/// The columns of `h_sweep.csv`, in order.
pub const H_SWEEP_COLUMNS: [&str; 9] = [
    "h",
    "max_nodal_distance",
    "h1_distance",
    "l2_distance",
    "contact_area",
    "contact_radius",
    "exact_max_distance",
    "iterations",
    "solve_s",
];

/// A column of a study's CSV file: floats (NaN for a missing value, written as an empty
/// field) or integers.
#[derive(Debug, Clone, PartialEq)]
pub enum StudyColumn {
    /// Floats; NaN where the value is missing.
    F(Vec<f64>),
    /// Integers.
    I(Vec<i32>),
}

/// The columns of `convergence.csv` for one study ([`CONVERGENCE_COLUMNS`]).
pub fn convergence_columns(s: &Study) -> Vec<(&'static str, StudyColumn)> {
    let rows = &s.levels;
    let f = |g: &dyn Fn(usize, &LevelResult) -> Option<f64>| -> StudyColumn {
        StudyColumn::F(
            rows.iter()
                .enumerate()
                .map(|(k, r)| g(k, r).unwrap_or(f64::NAN))
                .collect(),
        )
    };
    let i = |g: &dyn Fn(&LevelResult) -> usize| -> StudyColumn {
        StudyColumn::I(rows.iter().map(|r| g(r) as i32).collect())
    };
    let columns = [
        i(&|r| r.level),
        i(&|r| r.vertices),
        f(&|_, r| Some(r.l_n)),
        f(&|_, r| r.errors.map(|e| e.l2)),
        f(&|_, r| r.errors.map(|e| e.h1_semi)),
        f(&|_, r| r.errors.map(|e| e.max_nodal)),
        f(&|k, _| s.l2_rates[k]),
        f(&|k, _| s.h1_rates[k]),
        i(&|r| r.triangles),
        i(&|r| r.unknowns),
        f(&|k, _| s.max_nodal_rates[k]),
        f(&|_, r| Some(r.contact.area)),
        f(&|_, r| Some(r.contact.radius)),
        f(&|_, r| r.contact_area_error),
        f(&|_, r| r.contact_radius_error),
        f(&|_, r| r.errors.map(|e| e.gap_area)),
        f(&|_, r| r.errors.map(|e| e.gap_l2)),
        f(&|_, r| r.errors.map(|e| e.gap_h1_semi)),
        f(&|_, r| r.increment.map(|d| d[0])),
        f(&|_, r| r.increment.map(|d| d[1])),
        f(&|k, _| s.l2_increment_rates[k]),
        f(&|k, _| s.h1_increment_rates[k]),
        i(&|r| r.iterations),
        f(&|_, r| Some(r.kkt)),
        f(&|_, r| Some(r.assembly_seconds)),
        f(&|_, r| Some(r.solve_seconds)),
        f(&|_, r| Some(r.error_seconds)),
        f(&|_, r| r.epsilon),
    ];
    CONVERGENCE_COLUMNS.into_iter().zip(columns).collect()
}

/// The columns of `h_sweep.csv` ([`H_SWEEP_COLUMNS`]) of a rigid-limit sweep with the
/// exact distances (NaN where there is none).
pub fn h_sweep_columns(
    rows: &[RigidLimitRow],
    exact_distance: &[Option<f64>],
) -> Vec<(&'static str, StudyColumn)> {
    let col = |g: &dyn Fn(&RigidLimitRow) -> f64| StudyColumn::F(rows.iter().map(g).collect());
    let columns = [
        col(&|r| r.h),
        col(&|r| r.max_nodal),
        col(&|r| r.h1_semi),
        col(&|r| r.l2),
        col(&|r| r.contact.area),
        col(&|r| r.contact.radius),
        StudyColumn::F(
            exact_distance
                .iter()
                .map(|c| c.unwrap_or(f64::NAN))
                .collect(),
        ),
        StudyColumn::I(rows.iter().map(|r| r.iterations as i32).collect()),
        col(&|r| r.solve_seconds),
    ];
    H_SWEEP_COLUMNS.into_iter().zip(columns).collect()
}

/// Writes named columns as a CSV file, atomically.
pub fn write_study_csv(path: &Path, columns: &[(&str, StudyColumn)]) -> Result<()> {
    let arrays: Vec<(&str, DataArray)> = columns
        .iter()
        .map(|(name, c)| {
            (
                *name,
                match c {
                    StudyColumn::F(v) => DataArray::F64(v),
                    StudyColumn::I(v) => DataArray::I32(v),
                },
            )
        })
        .collect();
    write_columns_csv(path, &arrays)?;
    Ok(())
}

/// Writes the result set of a study into `target` as one (a directory holding other files
/// is refused unless `force`): the CSV files, the caller's pictures (`pictures` draws them
/// into the directory and returns their names), and `manifest.json`. Returns the names of
/// the files written.
pub fn write_study(
    target: &Path,
    force: bool,
    case: &Case,
    outcome: &StudyOutcome,
    pictures: &mut dyn FnMut(&Path) -> Result<Vec<String>>,
) -> Result<Vec<String>> {
    let set = ResultSet::begin(target, force)?;
    let mut written = Vec::new();
    let kind = match &outcome.result {
        StudyResult::Convergence(studies) => {
            for (v, s) in studies {
                let file = v.csv_name();
                write_study_csv(&set.dir().join(&file), &convergence_columns(s))?;
                written.push(file);
            }
            "convergence"
        }
        StudyResult::RigidLimit {
            sweep,
            exact_distance,
            ..
        } => {
            let file = "h_sweep.csv";
            write_study_csv(
                &set.dir().join(file),
                &h_sweep_columns(&sweep.rows, exact_distance),
            )?;
            written.push(file.to_string());
            "h sweep"
        }
    };
    written.extend(pictures(set.dir())?);
    write_manifest(set.dir(), kind, &new_run_id(), &input_hash(case))?;
    written.push(MANIFEST.into());
    set.commit()?;
    Ok(written)
}
