//! `Adapt`: the adaptive loop of a case with `[adapt]` (solve → estimate → mark → refine),
//! run by the library as `memcontact solve` runs it; its `write` writes the command-line
//! tool's result set (the final step's files, `adapt.csv`, `mesh.png`).

use crate::case::{case_on_mesh, PyCase};
use crate::convert::{py_err, to_py};
use crate::mesh::PyMesh;
use crate::result::{vtu_format, PyResult_};
use memcontact::adapt::AdaptRow;
use memcontact::adapt::{AdaptHistory, AdaptSet};
use memcontact::outcome::summary::AdaptTotals;
use memcontact::problem::{GivenMesh, MeshSource};
use memcontact::run::run_adapt;
use memcontact::solve::Silent;
use memcontact::write::WriteOptions;
use memcontact::write::{adapt_pictures, plot_options};
use memcontact::Case;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

/// The steps of an adaptive loop and its final result.
#[pyclass(name = "Adapt", module = "memcontact._memcontact", frozen)]
pub struct PyAdapt {
    label: String,
    case: Case,
    rows: Vec<AdaptRow>,
    indicators: Vec<f64>,
    totals: AdaptTotals,
    result: Py<PyResult_>,
    message: Option<String>,
}

/// What the loop produced, before it becomes Python objects.
struct Looped {
    rows: Vec<AdaptRow>,
    indicators: Vec<f64>,
    totals: AdaptTotals,
    result: PyResult_,
    message: Option<String>,
}

fn run_loop(case: &Case, label: &str) -> memcontact::Result<Looped> {
    let started = Instant::now();
    let run = run_adapt(case, &mut Silent, &mut |_, _, _| Ok(()))?;
    let totals = run.totals();
    let estimator: Vec<f64> = run.indicators.iter().map(|e| e.sqrt()).collect();
    let hierarchy = run.outcome.discretization.user_hierarchy();
    let mesh = PyMesh::new_from(hierarchy);
    // The result's case is what the last step solved: the data on the final mesh.
    let mut solved = case.clone();
    solved.adapt = None;
    solved.problem = run.problem;
    solved.problem.mesh.source = MeshSource::Given(GivenMesh::shared(Arc::clone(&mesh.hierarchy)));
    Ok(Looped {
        rows: run.rows,
        indicators: run.indicators,
        totals,
        result: PyResult_::with_estimator(
            label.to_string(),
            solved,
            mesh,
            run.outcome,
            started,
            Some(estimator),
        ),
        message: run.error.map(|e| e.to_string()),
    })
}

fn adapt_case(py: Python<'_>, mut c: Case, label: String) -> PyResult<PyAdapt> {
    if c.adapt.is_none() {
        return Err(PyValueError::new_err(
            "adapt: the case has no [adapt] section (give it one, e.g. {\"adapt\": \
             {\"max_vertices\": 30000}}, or solve it with memcontact.solve)",
        ));
    }
    let cancel = memcontact::Cancel::new();
    c.settings.cancel = cancel.clone();
    let (looped, c, label) = crate::convert::interruptible(py, &cancel, move || {
        let looped = run_loop(&c, &label)?;
        Ok((looped, c, label))
    })?;
    Ok(PyAdapt {
        label,
        case: c,
        rows: looped.rows,
        indicators: looped.indicators,
        totals: looped.totals,
        result: Py::new(py, looped.result)?,
        message: looped.message,
    })
}

/// Runs the adaptive loop of a case with `[adapt]`, with the GIL released. Bad data
/// raises `ValueError`; a step the settings do not accept ends the loop (its result is
/// the last).
#[pyfunction]
pub fn adapt(py: Python<'_>, case: PyRef<'_, PyCase>) -> PyResult<PyAdapt> {
    let (c, label) = (case.case.clone(), case.label.clone());
    drop(case);
    adapt_case(py, c, label)
}

/// Runs the adaptive loop of the case a dict describes (its sections but `mesh`, with
/// `adapt`) from `mesh`; data given as NumPy arrays of one value per vertex are
/// interpolated onto the new vertices (the totals' `adapt_interpolated` name them).
#[pyfunction]
#[pyo3(signature = (mesh, data, label=None))]
pub fn adapt_on(
    py: Python<'_>,
    mesh: PyRef<'_, PyMesh>,
    data: &Bound<'_, PyDict>,
    label: Option<String>,
) -> PyResult<PyAdapt> {
    let c = case_on_mesh(data, &mesh.hierarchy)?;
    drop(mesh);
    adapt_case(py, c, label.unwrap_or_else(|| "mesh".into()))
}

#[pymethods]
impl PyAdapt {
    /// The rows of `adapt.csv` (dicts with its columns, in its order), one per step.
    #[getter]
    fn rows<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let list = PyList::empty(py);
        for r in &self.rows {
            let value = serde_json::to_value(r)
                .map_err(|e| PyValueError::new_err(format!("cannot convert a row: {e}")))?;
            let row = PyDict::new(py);
            for column in AdaptRow::HEADER {
                row.set_item(column, crate::convert::to_py(py, &value[column])?)?;
            }
            list.append(row)?;
        }
        Ok(list)
    }

    /// The columns of `adapt.csv`, in order.
    #[getter]
    fn columns(&self) -> Vec<&'static str> {
        AdaptRow::HEADER.to_vec()
    }

    /// The last step's result (on the final mesh).
    #[getter]
    fn result(&self, py: Python<'_>) -> Py<PyResult_> {
        self.result.clone_ref(py)
    }

    /// The final mesh (with every step's mesh as its levels).
    #[getter]
    fn mesh<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.result.bind(py).getattr("mesh")
    }

    /// η_T of the last step, one per triangle of the final mesh (energy-norm units;
    /// `result.estimator`, read-only).
    #[getter]
    fn estimator<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.result.bind(py).getattr("estimator")
    }

    /// The loop's totals as in `summary.json` (`adapt_steps`, `adapt_estimator`,
    /// `adapt_stop`, `adapt_interpolated`, ...).
    #[getter]
    fn totals<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_py(py, &self.totals)
    }

    /// Why the loop stopped: `tolerance`, `steps`, `max_vertices`, `not_accepted` or
    /// `estimator_not_finite` or `memory`.
    #[getter]
    fn stop(&self) -> String {
        self.totals.adapt_stop.clone()
    }

    /// The data given per vertex that were interpolated onto new vertices.
    #[getter]
    fn interpolated(&self) -> Vec<String> {
        self.totals.adapt_interpolated.clone()
    }

    /// What stopped the loop early (a step not accepted, an estimator not finite), or None.
    #[getter]
    fn message(&self) -> Option<String> {
        self.message.clone()
    }

    /// Whether the last step was accepted by the settings.
    #[getter]
    fn accepted(&self) -> bool {
        self.result.get().data().report.accepted
    }

    /// The case run (with its `[adapt]` section).
    #[getter]
    fn case(&self) -> PyCase {
        PyCase {
            case: self.case.clone(),
            label: self.label.clone(),
        }
    }

    /// Writes the result set `memcontact solve` writes for this case into `directory`,
    /// atomically: the final step's `solution.vtu` (with the estimator per triangle),
    /// `nodes.csv`, the pictures (with `mesh.png`; none when `pictures` is false),
    /// `adapt.csv` and `summary.json` with the loop's totals. `vtu` ("binary", "ascii" or
    /// "compressed") defaults to the case's `[output] vtu`. A directory holding other files
    /// is refused unless `force`. Returns the summary.
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
        let summary = crate::convert::detached(py, || -> memcontact::Result<_> {
            let result = self.result.get();
            let outcome = result.outcome()?;
            let mut plots = plot_options(&self.case, &self.label);
            if !pictures {
                plots.plots.clear();
            }
            let options = WriteOptions {
                label: self.label.clone(),
                vtu,
                force,
                started: Instant::now(),
                plot_options: serde_json::to_value(&plots).ok(),
                run_id: None,
                cell_data: Vec::new(),
                adapt: None,
                unconverged: false,
            };
            let history = AdaptHistory {
                rows: &self.rows,
                indicators: &self.indicators,
                totals: &self.totals,
            };
            let mesh = outcome.mesh();
            let mut pictures = adapt_pictures(&mesh, &plots);
            let summary = AdaptSet::begin(&directory, force)?.finish(
                &self.case,
                &outcome,
                history,
                &options,
                &mut pictures,
            )?;
            Ok(summary)
        })
        .map_err(py_err)?;
        to_py(py, &summary)
    }

    /// The rows as a `pandas.DataFrame` with the columns of the CSV file (see
    /// `memcontact._notebook.to_pandas`).
    fn to_pandas<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        crate::convert::call_helper(slf.py(), "to_pandas", (slf,), None)
    }

    /// The notebook's summary and table of rows (HTML).
    fn _repr_html_<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        crate::convert::call_helper(slf.py(), "adapt_html", (slf,), None)
    }

    fn __len__(&self) -> usize {
        self.rows.len()
    }

    fn __repr__(&self) -> String {
        format!(
            "Adapt({:?}, {} steps, {} → {} vertices, estimator {:.3e}, stopped: {})",
            self.label,
            self.rows.len(),
            self.rows.first().map_or(0, |r| r.vertices),
            self.rows.last().map_or(0, |r| r.vertices),
            self.totals.adapt_estimator,
            self.totals.adapt_stop
        )
    }
}
