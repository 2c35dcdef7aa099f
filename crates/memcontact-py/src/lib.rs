//! The `memcontact` Python module's native part (`memcontact._memcontact`): cases,
//! meshes as NumPy arrays, solves with the GIL released, results that pickle. The typed
//! Python package `memcontact` wraps it.

mod case;
mod convert;
mod mesh;
mod result;

use case::PyCase;
use convert::py_err;
use memcontact::solve::Silent;
use memcontact::{Discretization, Outcome};
use mesh::PyMesh;
use pyo3::prelude::*;
use result::PyResult_;
use std::time::Instant;

/// Solves a case end to end (mesh, assembly, solve) with the GIL released. Returns the
/// result whatever the status; bad data raises `ValueError`.
#[pyfunction]
fn solve(py: Python<'_>, case: PyRef<'_, PyCase>) -> PyResult<PyResult_> {
    let c = case.case.clone();
    let label = case.label.clone();
    drop(case);
    py.detach(move || {
        let started = Instant::now();
        let outcome = memcontact::run(&c.problem, &c.settings, &mut Silent)?;
        let mesh = PyMesh::new_from(outcome.discretization.hierarchy.clone());
        Ok(PyResult_::new(label, c, mesh, outcome, started))
    })
    .map_err(py_err)
}

/// Solves the problem of `case` (its mesh section is not used) on `mesh`, with the GIL
/// released. Returns the result whatever the status.
#[pyfunction]
fn solve_on(
    py: Python<'_>,
    mesh: PyRef<'_, PyMesh>,
    case: PyRef<'_, PyCase>,
) -> PyResult<PyResult_> {
    let c = case.case.clone();
    let label = case.label.clone();
    let mesh = mesh.clone();
    py.detach(move || {
        let started = Instant::now();
        c.settings
            .validate()
            .map_err(memcontact::problem::Invalid::into_error)?;
        let discretization =
            Discretization::assemble(&c.problem, (*mesh.hierarchy).clone(), &mut Silent)?;
        let report = discretization.solve(&c.settings, &mut Silent)?;
        let outcome = Outcome {
            discretization,
            report,
        };
        Ok(PyResult_::new(label, c, mesh, outcome, started))
    })
    .map_err(py_err)
}

/// The native module.
#[pymodule]
fn _memcontact(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyCase>()?;
    m.add_class::<PyMesh>()?;
    m.add_class::<PyResult_>()?;
    m.add_function(wrap_pyfunction!(solve, m)?)?;
    m.add_function(wrap_pyfunction!(solve_on, m)?)?;
    m.add_function(wrap_pyfunction!(mesh::rectangle, m)?)?;
    m.add_function(wrap_pyfunction!(mesh::disk, m)?)?;
    m.add_function(wrap_pyfunction!(mesh::polygon, m)?)?;
    m.add_function(wrap_pyfunction!(mesh::read_gmsh, m)?)?;
    m.add_function(wrap_pyfunction!(mesh::_mesh_from_state, m)?)?;
    m.add_function(wrap_pyfunction!(result::_result_from_state, m)?)?;
    m.add_function(wrap_pyfunction!(case::_toml_value, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
