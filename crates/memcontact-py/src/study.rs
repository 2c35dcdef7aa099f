//! `Study`: a convergence study of a case (or its rigid-limit sweep), run by the library as
//! `memcontact convergence` runs it; its `write` writes the command-line tool's files.

use crate::case::PyCase;
use crate::convert::py_err;
use memcontact::verify::study::{run_study, Compare, StudyOptions, StudyOutcome, StudyResult};
use memcontact::write::{convergence_columns, h_sweep_columns, write_study, StudyColumn};
use memcontact::Case;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::path::PathBuf;

/// The result of a convergence study: the rows of `convergence.csv` (or `h_sweep.csv`),
/// one dict per level (or stiffness) keyed by the file's columns with its values (a missing
/// value, an empty field in the file, is None).
#[pyclass(name = "Study", module = "memcontact._memcontact", frozen)]
pub struct PyStudy {
    case: Case,
    label: String,
    outcome: StudyOutcome,
}

/// The rows of named columns as a list of dicts (NaN floats: None).
fn rows<'py>(py: Python<'py>, columns: &[(&str, StudyColumn)]) -> PyResult<Bound<'py, PyList>> {
    let n = columns.first().map_or(0, |(_, c)| match c {
        StudyColumn::F(v) => v.len(),
        StudyColumn::I(v) => v.len(),
    });
    let list = PyList::empty(py);
    for k in 0..n {
        let row = PyDict::new(py);
        for (name, c) in columns {
            match c {
                StudyColumn::F(v) if v[k].is_nan() => row.set_item(name, py.None())?,
                StudyColumn::F(v) => row.set_item(name, v[k])?,
                StudyColumn::I(v) => row.set_item(name, v[k])?,
            }
        }
        list.append(row)?;
    }
    Ok(list)
}

/// Runs the convergence study of `case` with `levels` refinements (`compare`:
/// "foundation" or "sampling"; `h_sweep`: the rigid-limit sweep with the stiffnesses
/// `h_values`, default 10, ..., 1e6), with the GIL released.
#[pyfunction]
#[pyo3(signature = (case, levels, compare=None, h_sweep=false, h_values=None))]
pub fn convergence(
    py: Python<'_>,
    case: PyRef<'_, PyCase>,
    levels: usize,
    compare: Option<&str>,
    h_sweep: bool,
    h_values: Option<Vec<f64>>,
) -> PyResult<PyStudy> {
    let compare = match compare {
        None => None,
        Some("foundation") => Some(Compare::Foundation),
        Some("sampling") => Some(Compare::Sampling),
        Some(other) => {
            return Err(PyValueError::new_err(format!(
                "compare must be \"foundation\" or \"sampling\", not \"{other}\""
            )))
        }
    };
    if h_values.is_some() && !h_sweep {
        return Err(PyValueError::new_err("h_values needs h_sweep=True"));
    }
    if h_sweep && compare.is_some() {
        return Err(PyValueError::new_err(
            "compare and h_sweep cannot be combined",
        ));
    }
    let options = StudyOptions {
        levels,
        compare,
        h_sweep: h_sweep.then(|| h_values.unwrap_or_default()),
    };
    let (mut c, label) = (case.case.clone(), case.label.clone());
    drop(case);
    let cancel = memcontact::Cancel::new();
    c.settings.cancel = cancel.clone();
    let outcome = crate::convert::interruptible(py, &cancel, || {
        run_study(&c, &options, &mut |_, _| {}, &mut |_, _| {})
    })?;
    Ok(PyStudy {
        case: c,
        label,
        outcome,
    })
}

#[pymethods]
impl PyStudy {
    /// `"convergence"` or `"h sweep"`.
    #[getter]
    fn kind(&self) -> &'static str {
        match self.outcome.result {
            StudyResult::Convergence(_) => "convergence",
            StudyResult::RigidLimit { .. } => "h sweep",
        }
    }

    /// The rows of `convergence.csv` (of the first variant when comparing) or of
    /// `h_sweep.csv`, as dicts keyed by its columns.
    #[getter]
    fn rows<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        match &self.outcome.result {
            StudyResult::Convergence(studies) => rows(py, &convergence_columns(&studies[0].1)),
            StudyResult::RigidLimit {
                sweep,
                exact_distance,
                ..
            } => rows(py, &h_sweep_columns(&sweep.rows, exact_distance)),
        }
    }

    /// The rows of every variant by its file name (`convergence.csv`, or
    /// `convergence-consistent.csv` and `convergence-lumped.csv`, ...).
    #[getter]
    fn variants<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        if let StudyResult::Convergence(studies) = &self.outcome.result {
            for (v, s) in studies {
                d.set_item(v.csv_name(), rows(py, &convergence_columns(s))?)?;
            }
        }
        Ok(d)
    }

    /// The exact solution the errors are measured against (None: the finest level's).
    #[getter]
    fn exact(&self) -> Option<String> {
        self.outcome.exact.as_ref().map(|e| e.solution().describe())
    }

    /// Warnings from reading the mesh.
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.outcome.warnings.clone()
    }

    /// Writes the files `memcontact convergence` writes into `directory`, atomically: the
    /// CSV files, `convergence.png` or `h_sweep.png` (unless `pictures` is false) and
    /// `manifest.json`. A directory holding other files is refused unless `force`. Returns
    /// the names of the files written.
    #[pyo3(signature = (directory, force=false, pictures=true))]
    fn write(
        &self,
        py: Python<'_>,
        directory: PathBuf,
        force: bool,
        pictures: bool,
    ) -> PyResult<Vec<String>> {
        let file_name = std::path::Path::new(&self.label)
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| self.label.clone());
        crate::convert::detached(py, || {
            write_study(&directory, force, &self.case, &self.outcome, &mut |dir| {
                if pictures {
                    memcontact::write::study_pictures(dir, &self.outcome, &file_name)
                } else {
                    Ok(Vec::new())
                }
            })
        })
        .map_err(py_err)
    }

    /// The columns of `convergence.csv` (or `h_sweep.csv`), in order.
    #[getter]
    fn columns(&self) -> Vec<&'static str> {
        let names = |c: Vec<(&'static str, StudyColumn)>| c.into_iter().map(|(n, _)| n).collect();
        match &self.outcome.result {
            StudyResult::Convergence(studies) => names(convergence_columns(&studies[0].1)),
            StudyResult::RigidLimit {
                sweep,
                exact_distance,
                ..
            } => names(h_sweep_columns(&sweep.rows, exact_distance)),
        }
    }

    /// The rows of one CSV file (`variant`: a file name of `variants`; default the
    /// first, the file of `rows`) as a `pandas.DataFrame` with its columns (see
    /// `memcontact._notebook.to_pandas`).
    #[pyo3(signature = (variant=None))]
    fn to_pandas<'py>(
        slf: &Bound<'py, Self>,
        variant: Option<&str>,
    ) -> PyResult<Bound<'py, PyAny>> {
        crate::convert::call_helper(slf.py(), "to_pandas", (slf, variant), None)
    }

    /// The notebook's summary and table of rows (HTML).
    fn _repr_html_<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        crate::convert::call_helper(slf.py(), "study_html", (slf,), None)
    }

    fn __len__(&self) -> usize {
        match &self.outcome.result {
            StudyResult::Convergence(studies) => studies[0].1.levels.len(),
            StudyResult::RigidLimit { sweep, .. } => sweep.rows.len(),
        }
    }

    fn __repr__(&self) -> String {
        format!(
            "Study({:?}, {}, {} rows)",
            self.label,
            self.kind(),
            self.__len__()
        )
    }
}
