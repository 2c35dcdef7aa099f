//! The `memcontact` Python module's native part (`memcontact._memcontact`): cases,
//! meshes as NumPy arrays, solves and sweeps with the GIL released, results that pickle. The
//! typed Python package `memcontact` wraps it.

mod adapt;
mod case;
mod convert;
mod mesh;
mod result;
mod sensitivity;
mod study;
mod sweep;
mod views;

use case::PyCase;
use convert::interruptible;
use memcontact::solve::Silent;
use mesh::PyMesh;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use result::PyResult_;
use std::time::Instant;

/// A case with steps is refused by `solve` (which would solve its base case alone), and so
/// is a case with `[adapt]` (its loop is `adapt`).
fn refuse_sweep(case: &memcontact::Case) -> PyResult<()> {
    if case.adapt.is_some() {
        return Err(PyValueError::new_err(
            "the case has [adapt]: run its adaptive loop with memcontact.adapt(case)",
        ));
    }
    if !case.is_sweep() {
        return Ok(());
    }
    let what = if case.sweep.is_some() {
        "a [sweep]"
    } else {
        "[[load_case]] entries"
    };
    Err(PyValueError::new_err(format!(
        "the case has {what}: solve would solve only its base case; solve every step with \
         memcontact.sweep(case)"
    )))
}

/// Solves a case end to end (mesh, assembly, checks on the mesh, solve:
/// `memcontact::run`) with the GIL released. Returns the result whatever the status; bad
/// data raises `ValueError`, and so does a case with steps (`[sweep]`, `[[load_case]]`:
/// see `sweep`).
#[pyfunction]
fn solve(py: Python<'_>, case: PyRef<'_, PyCase>) -> PyResult<PyResult_> {
    refuse_sweep(&case.case)?;
    let mut c = case.case.clone();
    let label = case.label.clone();
    drop(case);
    let cancel = memcontact::Cancel::new();
    c.settings.cancel = cancel.clone();
    interruptible(py, &cancel, move || {
        let started = Instant::now();
        let outcome = memcontact::run(&c, &mut Silent)?;
        let mesh = PyMesh::new_from(outcome.discretization.user_hierarchy());
        Ok(PyResult_::new(label, c, mesh, outcome, started))
    })
}

/// Solves the case a dict describes (the sections of a case file but `mesh`) on `mesh`,
/// given as data (`MeshSource::Given`), with the GIL released. The dict's data may be
/// NumPy arrays of one value per vertex (`membrane.load`, `obstacle.shape`,
/// `obstacle.stiffness`, `boundary.height`, `lower.shape`, `lower.stiffness`). Returns
/// the result whatever the status.
#[pyfunction]
#[pyo3(signature = (mesh, data, label=None))]
fn solve_on(
    py: Python<'_>,
    mesh: PyRef<'_, PyMesh>,
    data: &Bound<'_, PyDict>,
    label: Option<String>,
) -> PyResult<PyResult_> {
    let mesh = mesh.clone();
    let mut c = case::case_on_mesh(data, &mesh.hierarchy)?;
    refuse_sweep(&c)?;
    let label = label.unwrap_or_else(|| "mesh".into());
    let cancel = memcontact::Cancel::new();
    c.settings.cancel = cancel.clone();
    interruptible(py, &cancel, move || {
        let started = Instant::now();
        let outcome = memcontact::run(&c, &mut Silent)?;
        Ok(PyResult_::new(label, c, mesh, outcome, started))
    })
}

/// The case a dict describes (the sections of a case file but `mesh`) on `mesh`, given as
/// data, as `solve_on` makes it: for the runs that take a `Case` (sensitivities, fits).
#[pyfunction]
#[pyo3(signature = (mesh, data, label=None))]
fn case_on(
    mesh: PyRef<'_, PyMesh>,
    data: &Bound<'_, PyDict>,
    label: Option<String>,
) -> PyResult<PyCase> {
    let case = case::case_on_mesh(data, &mesh.hierarchy)?;
    Ok(PyCase {
        case,
        label: label.unwrap_or_else(|| "mesh".into()),
    })
}

/// The sections of a case file as a dict (the TOML parsed, nothing checked yet): for a
/// case file without `[mesh]` solved on a mesh given as data.
#[pyfunction]
fn _case_table<'py>(py: Python<'py>, path: std::path::PathBuf) -> PyResult<Bound<'py, PyAny>> {
    let text = memcontact::case::read_case_text(&path).map_err(convert::py_err)?;
    let table: toml::Table = toml::from_str(&text).map_err(|e| {
        PyValueError::new_err(format!(
            "{}: malformed TOML: {}",
            path.display(),
            e.message().trim()
        ))
    })?;
    convert::to_py(py, &table)
}

/// The native module.
#[pymodule]
fn _memcontact(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyCase>()?;
    m.add_class::<PyMesh>()?;
    m.add_class::<PyResult_>()?;
    m.add_class::<sweep::PySweep>()?;
    m.add_class::<study::PyStudy>()?;
    m.add_class::<adapt::PyAdapt>()?;
    m.add_class::<sensitivity::PySensitivities>()?;
    m.add_class::<sensitivity::PyFit>()?;
    m.add_class::<sensitivity::PyFitProblem>()?;
    m.add_function(wrap_pyfunction!(solve, m)?)?;
    m.add_function(wrap_pyfunction!(sensitivity::sensitivities, m)?)?;
    m.add_function(wrap_pyfunction!(sensitivity::fit, m)?)?;
    m.add_function(wrap_pyfunction!(sensitivity::fit_problem, m)?)?;
    m.add_function(wrap_pyfunction!(case_on, m)?)?;
    m.add_function(wrap_pyfunction!(sweep::sweep, m)?)?;
    m.add_function(wrap_pyfunction!(study::convergence, m)?)?;
    m.add_function(wrap_pyfunction!(solve_on, m)?)?;
    m.add_function(wrap_pyfunction!(adapt::adapt, m)?)?;
    m.add_function(wrap_pyfunction!(adapt::adapt_on, m)?)?;
    m.add_function(wrap_pyfunction!(mesh::rectangle, m)?)?;
    m.add_function(wrap_pyfunction!(mesh::disk, m)?)?;
    m.add_function(wrap_pyfunction!(mesh::polygon, m)?)?;
    m.add_function(wrap_pyfunction!(mesh::read_gmsh, m)?)?;
    m.add_function(wrap_pyfunction!(mesh::_mesh_from_state, m)?)?;
    m.add_function(wrap_pyfunction!(result::_result_from_state, m)?)?;
    m.add_function(wrap_pyfunction!(case::_toml_value, m)?)?;
    m.add_function(wrap_pyfunction!(_case_table, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
