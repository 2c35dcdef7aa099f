//! The `memcontact` Python module's native part (`memcontact._memcontact`): cases,
//! meshes as NumPy arrays, solves and sweeps with the GIL released, results that pickle. The
//! typed Python package `memcontact` wraps it.

mod case;
mod convert;
mod mesh;
mod result;
mod sweep;

use case::PyCase;
use convert::py_err;
use memcontact::field::{Field, Stiffness};
use memcontact::solve::Silent;
use memcontact::Invalid;
use memcontact::{Discretization, Outcome};
use mesh::PyMesh;
use numpy::PyReadonlyArray1;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use result::PyResult_;
use std::collections::HashMap;
use std::time::Instant;

/// A case with steps is refused by `solve` (which would solve its base case alone).
fn refuse_sweep(case: &memcontact::Case) -> PyResult<()> {
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

/// Solves a case end to end (mesh, assembly, checks on the mesh, solve) with the GIL
/// released. Returns the result whatever the status; bad data raises `ValueError`, and so
/// does a case with steps (`[sweep]`, `[[load_case]]`: see `sweep`).
#[pyfunction]
fn solve(py: Python<'_>, case: PyRef<'_, PyCase>) -> PyResult<PyResult_> {
    refuse_sweep(&case.case)?;
    let c = case.case.clone();
    let label = case.label.clone();
    drop(case);
    py.detach(move || {
        memcontact::on_workers(move || {
            let started = Instant::now();
            c.settings.validate().map_err(Invalid::into_error)?;
            let outcome = memcontact_plot::write::solve_case(&c, &mut Silent)?;
            let mesh = PyMesh::new_from(outcome.discretization.user_hierarchy());
            Ok(PyResult_::new(label, c, mesh, outcome, started))
        })
    })
    .map_err(py_err)
}

/// Solves the problem of `case` (its mesh section is not used) on `mesh`, with the GIL
/// released. `nodal` gives data as NumPy arrays of one value per vertex ("load", "shape",
/// "stiffness"), replacing the case's. Returns the result whatever the status.
#[pyfunction]
#[pyo3(signature = (mesh, case, nodal=None))]
fn solve_on(
    py: Python<'_>,
    mesh: PyRef<'_, PyMesh>,
    case: PyRef<'_, PyCase>,
    nodal: Option<HashMap<String, PyReadonlyArray1<'_, f64>>>,
) -> PyResult<PyResult_> {
    refuse_sweep(&case.case)?;
    let mut c = case.case.clone();
    let label = case.label.clone();
    let mesh = mesh.clone();
    for (name, values) in nodal.unwrap_or_default() {
        let field = Field::Nodal(values.as_array().iter().copied().collect());
        match (name.as_str(), c.problem.lower.as_mut()) {
            ("load", _) => c.problem.membrane.load = field,
            ("shape", _) => c.problem.obstacle.shape = field,
            ("stiffness", _) => c.problem.obstacle.stiffness = Stiffness::Elastic(field),
            ("height", _) => c.problem.boundary.height = field,
            ("lower_shape", Some(low)) => low.shape = field,
            ("lower_stiffness", Some(low)) => low.stiffness = Stiffness::Elastic(field),
            (other, _) => {
                return Err(PyValueError::new_err(format!(
                    "nodal: \"{other}\" is not a field (load, shape, stiffness, height, \
                     lower_shape or lower_stiffness with a body below)"
                )))
            }
        }
    }
    py.detach(move || {
        memcontact::on_workers(move || {
            let started = Instant::now();
            c.problem.validate().map_err(Invalid::into_error)?;
            c.settings.validate().map_err(Invalid::into_error)?;
            let discretization =
                Discretization::assemble(&c.problem, (*mesh.hierarchy).clone(), &mut Silent)?;
            memcontact_plot::write::check_on_mesh(&c, discretization.mesh())?;
            let report = discretization.solve(&c.settings, &mut Silent)?;
            let outcome = Outcome {
                discretization,
                report,
            };
            Ok(PyResult_::new(label, c, mesh, outcome, started))
        })
    })
    .map_err(py_err)
}

/// The native module.
#[pymodule]
fn _memcontact(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyCase>()?;
    m.add_class::<PyMesh>()?;
    m.add_class::<PyResult_>()?;
    m.add_class::<sweep::PySweep>()?;
    m.add_function(wrap_pyfunction!(solve, m)?)?;
    m.add_function(wrap_pyfunction!(sweep::sweep, m)?)?;
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
