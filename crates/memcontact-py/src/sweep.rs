//! `Sweep`: the steps of a case's `[sweep]` or `[[load_case]]` entries, solved in turn on
//! one mesh (each warm-started from the previous answer), as `memcontact solve` solves
//! them; its `write` writes the command-line tool's result set.

use crate::case::PyCase;
use crate::convert::{py_err, to_py};
use crate::mesh::PyMesh;
use crate::result::{vtu_format, PyResult_};
use memcontact::case::StepSpec;
use memcontact::outcome::StepRow;
use memcontact::run::run_sweep;
use memcontact::solve::Silent;
use memcontact::write::step_label;
use memcontact::write::SweepWriter;
use memcontact::{Case, Error};
use pyo3::exceptions::{PyIndexError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::path::PathBuf;

/// The solved steps of a sweep (or of load cases): one `Result` per step, the rows of
/// `sweep.csv`, and, when a step was not accepted, its message (the sweep stopped there).
#[pyclass(name = "Sweep", module = "memcontact._memcontact", frozen)]
pub struct PySweep {
    label: String,
    case: Case,
    steps: Vec<StepSpec>,
    results: Vec<Py<PyResult_>>,
    rows: Vec<StepRow>,
    message: Option<String>,
}

/// What the solve of a sweep produced, before it becomes Python objects.
struct Solved {
    results: Vec<PyResult_>,
    steps: Vec<StepSpec>,
    rows: Vec<StepRow>,
    message: Option<String>,
}

fn solve_steps(case: &Case, label: &str, warm: bool) -> memcontact::Result<Solved> {
    if !case.is_sweep() {
        return Err(Error::Data(
            "the case has no [sweep] and no [[load_case]] entries: solve it with \
             memcontact.solve(case)"
                .into(),
        ));
    }
    let mut mesh: Option<PyMesh> = None;
    let mut results = Vec::new();
    let run = run_sweep(case, warm, &mut Silent, &mut |step, outcome, row| {
        let mesh =
            mesh.get_or_insert_with(|| PyMesh::new_from(outcome.discretization.user_hierarchy()));
        results.push(PyResult_::of_step(
            step_label(label, step),
            case.clone(),
            mesh.clone(),
            outcome,
            row.seconds,
            step.index,
        ));
        Ok(())
    })?;
    Ok(Solved {
        results,
        steps: run.steps,
        rows: run.rows,
        // A step the settings do not accept ends the sweep: its result is kept.
        message: run.stopped.map(|(_, e)| e.to_string()),
    })
}

/// Solves the steps of a case with `[sweep]` or `[[load_case]]` in turn on one mesh, each
/// warm-started from the previous answer (`warm=False`: each from the usual start), with
/// the GIL released. A step that is not accepted ends the sweep (its result is the last);
/// bad data raises `ValueError`.
#[pyfunction]
#[pyo3(signature = (case, warm=true))]
pub fn sweep(py: Python<'_>, case: PyRef<'_, PyCase>, warm: bool) -> PyResult<PySweep> {
    let mut c = case.case.clone();
    let label = case.label.clone();
    drop(case);
    let cancel = memcontact::Cancel::new();
    c.settings.cancel = cancel.clone();
    let (solved, c, label) = crate::convert::interruptible(py, &cancel, move || {
        let solved = solve_steps(&c, &label, warm)?;
        Ok((solved, c, label))
    })?;
    let results = solved
        .results
        .into_iter()
        .map(|r| Py::new(py, r))
        .collect::<PyResult<Vec<_>>>()?;
    Ok(PySweep {
        label,
        case: c,
        steps: solved.steps,
        results,
        rows: solved.rows,
        message: solved.message,
    })
}

#[pymethods]
impl PySweep {
    /// The results of the steps solved, in order (all of them unless a step was not
    /// accepted: then that step's result is the last).
    #[getter]
    fn results<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        PyList::new(py, self.results.iter().map(|r| r.clone_ref(py)))
    }

    /// The rows of `sweep.csv` (dicts with its columns, in its order), one per step
    /// solved.
    #[getter]
    fn rows<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let list = PyList::empty(py);
        for r in &self.rows {
            let value = serde_json::to_value(r)
                .map_err(|e| PyValueError::new_err(format!("cannot convert a row: {e}")))?;
            let row = PyDict::new(py);
            for column in StepRow::HEADER {
                row.set_item(column, to_py(py, &value[column])?)?;
            }
            list.append(row)?;
        }
        Ok(list)
    }

    /// The columns of `sweep.csv`, in order.
    #[getter]
    fn columns(&self) -> Vec<&'static str> {
        StepRow::HEADER.to_vec()
    }

    /// What varies: the `[sweep]` parameter (`load_factor`, `stiffness_factor`,
    /// `tension`, `obstacle_offset`), or `load_case`.
    #[getter]
    fn parameter(&self) -> &'static str {
        match &self.case.sweep {
            Some(s) => s.parameter.name(),
            None => "load_case",
        }
    }

    /// The names of all the case's steps (`step-000`, ... or the load cases' names), which
    /// are also the directories `write` creates.
    #[getter]
    fn names(&self) -> Vec<String> {
        self.steps.iter().map(|s| s.name.clone()).collect()
    }

    /// The values of all the case's steps (the swept value, or a load case's load factor).
    #[getter]
    fn values(&self) -> Vec<f64> {
        self.steps.iter().map(|s| s.value).collect()
    }

    /// Whether every step was solved and accepted.
    #[getter]
    fn accepted(&self) -> bool {
        self.message.is_none() && self.results.len() == self.steps.len()
    }

    /// Why the sweep stopped early (None when every step was accepted).
    #[getter]
    fn message(&self) -> Option<String> {
        self.message.clone()
    }

    /// The case swept.
    #[getter]
    fn case(&self) -> PyCase {
        PyCase {
            case: self.case.clone(),
            label: self.label.clone(),
        }
    }

    /// Writes the result set the command-line tool writes for this case into
    /// `directory`, atomically: a directory per step solved (`step-000`, ... or the load
    /// case's name) with `solution.vtu`, `nodes.csv`, the pictures of the case's `[output]
    /// plots` (unless `pictures` is false) and `summary.json`; then `sweep.csv` and
    /// `sweep.png`. `vtu` ("binary", "ascii" or "compressed") defaults to the case's
    /// `[output] vtu`. A directory holding other files is refused unless `force`. Returns
    /// the steps' summaries.
    #[pyo3(signature = (directory, force=false, vtu=None, pictures=true))]
    fn write<'py>(
        &self,
        py: Python<'py>,
        directory: PathBuf,
        force: bool,
        vtu: Option<&str>,
        pictures: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        let vtu = vtu_format(vtu, &self.case)?;
        let summaries = crate::convert::detached(py, || -> memcontact::Result<_> {
            let mut writer =
                SweepWriter::begin(&directory, force, &self.case, &self.label, vtu, pictures)?;
            let mut summaries = Vec::with_capacity(self.results.len());
            for (result, row) in self.results.iter().zip(&self.rows) {
                let outcome = result.get().outcome()?;
                let step = &self.steps[row.step];
                summaries.push(writer.write_step(&self.case, step, &outcome, row.seconds)?);
            }
            writer.finish(&self.rows)?;
            Ok(summaries)
        })
        .map_err(py_err)?;
        to_py(py, &summaries)
    }

    /// The rows as a `pandas.DataFrame` with the columns of the CSV file (see
    /// `memcontact._notebook.to_pandas`).
    fn to_pandas<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        crate::convert::call_helper(slf.py(), "to_pandas", (slf,), None)
    }

    /// The notebook's summary and table of rows (HTML).
    fn _repr_html_<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        crate::convert::call_helper(slf.py(), "sweep_html", (slf,), None)
    }

    fn __len__(&self) -> usize {
        self.results.len()
    }

    fn __getitem__(&self, py: Python<'_>, index: &Bound<'_, PyAny>) -> PyResult<Py<PyResult_>> {
        let n = self.results.len() as isize;
        let index: isize = index
            .call_method0("__index__")
            .map_err(|_| {
                pyo3::exceptions::PyTypeError::new_err(format!(
                    "a sweep's steps are indexed by integers, not {}",
                    index
                        .get_type()
                        .name()
                        .map(|n| n.to_string())
                        .unwrap_or_default()
                ))
            })?
            .extract()
            .map_err(|_| {
                PyIndexError::new_err(format!("step {index} is not one of the {n} steps solved"))
            })?;
        let i = if index < 0 { index + n } else { index };
        if !(0..n).contains(&i) {
            return Err(PyIndexError::new_err(format!(
                "step {index} is not one of the {n} steps solved"
            )));
        }
        Ok(self.results[i as usize].clone_ref(py))
    }

    fn __repr__(&self) -> String {
        format!(
            "Sweep({:?}, {}, {}/{} steps solved{})",
            self.label,
            self.parameter(),
            self.results.len(),
            self.steps.len(),
            if self.accepted() {
                String::new()
            } else {
                ", not accepted".to_string()
            }
        )
    }
}
