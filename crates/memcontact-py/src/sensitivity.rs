//! `Sensitivities`, `Fit` and `FitProblem`: the derivatives of a case's outputs in its
//! parameters, the back-analysis of measured deflections, and the fit's model for an
//! optimiser of the caller's (`scipy.optimize.least_squares`), run by the library as
//! `memcontact solve` runs a case with `[sensitivity]` or `[fit]`
//! (docs/sensitivities.md).

use crate::case::PyCase;
use crate::convert::{interruptible, py_err, to_py};
use crate::mesh::PyMesh;
use crate::result::{vtu_format, PyResult_};
use crate::views::{owned1, owned2, Cache};
use memcontact::fit::FitResult;
use memcontact::run::FitProblem;
use memcontact::sensitivity::{Request, Sensitivities};
use memcontact::solve::Silent;
use memcontact::write::{self, WriteOptions};
use memcontact::{Case, Error};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::path::PathBuf;
use std::sync::Mutex;
use std::time::Instant;

/// The columns of [`PySensitivities::rows`] after those of `sensitivity.csv`: the earlier
/// names of its `biactive` and `parameter_kind`, kept for code written against them.
const EARLIER_COLUMNS: [&str; 2] = ["nonsmooth", "kind"];

/// The columns of `fit.csv`'s rows as [`PyFit::rows`] gives them (then one per parameter).
const FIT_COLUMNS: [&str; 5] = ["iteration", "rms", "step", "damping", "solves"];

/// A NaN as None (for the rows: the CSV leaves those cells empty).
fn cell(py: Python<'_>, v: f64) -> PyResult<Bound<'_, PyAny>> {
    if v.is_finite() {
        Ok(v.into_pyobject(py)?.into_any())
    } else {
        Ok(py.None().into_bound(py))
    }
}

/// The derivatives of a case's outputs in its parameters, with the solve they were taken at.
#[pyclass(name = "Sensitivities", module = "memcontact._memcontact", frozen)]
pub struct PySensitivities {
    label: String,
    case: Case,
    s: Sensitivities,
    result: Py<PyResult_>,
    cache: Cache<8>,
}

/// The case with the request's outputs and parameters, checked like a case file's
/// `[sensitivity]`.
fn request_of(
    case: &Case,
    outputs: Option<Vec<String>>,
    parameters: Option<Vec<String>>,
    influence: bool,
) -> PyResult<Request> {
    let spec = case.sensitivity.as_ref();
    let outputs = outputs
        .or_else(|| spec.map(|s| s.outputs.clone()))
        .ok_or_else(|| {
            PyValueError::new_err(
                "sensitivities: give outputs= (or a [sensitivity] section with outputs)",
            )
        })?;
    let parameters = parameters
        .or_else(|| spec.map(|s| s.parameters.clone()))
        .ok_or_else(|| {
            PyValueError::new_err(
                "sensitivities: give parameters= (or a [sensitivity] section with parameters)",
            )
        })?;
    Ok(Request {
        outputs,
        parameters,
        influence,
    })
}

/// Solves `case` and differentiates the request's outputs in its parameters, with the GIL
/// released (`memcontact::run::run_request`). An unaccepted solve raises `SolverError`
/// in the Python wrapper (the result is returned without derivatives here: `None`).
#[pyfunction]
#[pyo3(signature = (case, outputs=None, parameters=None, influence=true))]
pub fn sensitivities(
    py: Python<'_>,
    case: PyRef<'_, PyCase>,
    outputs: Option<Vec<String>>,
    parameters: Option<Vec<String>>,
    influence: bool,
) -> PyResult<(Option<PySensitivities>, Py<PyResult_>)> {
    let mut c = case.case.clone();
    let label = case.label.clone();
    drop(case);
    let request = request_of(&c, outputs, parameters, influence)?;
    let cancel = memcontact::Cancel::new();
    c.settings.cancel = cancel.clone();
    let solved = c.clone();
    let result_label = label.clone();
    let (s, result) = interruptible(py, &cancel, move || {
        let started = Instant::now();
        let run = memcontact::run::run_request(&c, &request, &mut Silent)?;
        let mesh = PyMesh::new_from(run.outcome.discretization.user_hierarchy());
        let result = PyResult_::new(result_label, c, mesh, run.outcome, started);
        Ok((run.sensitivities, result))
    })?;
    let result = Py::new(py, result)?;
    let s = s.map(|s| PySensitivities {
        label,
        case: solved,
        s,
        result: result.clone_ref(py),
        cache: Cache::default(),
    });
    Ok((s, result))
}

impl PySensitivities {
    fn n_parameters(&self) -> usize {
        self.s.parameters.len()
    }
}

#[pymethods]
impl PySensitivities {
    /// The outputs' names (`energy`, `sensor:NAME`, `contact_force:REGION`, ...), the rows
    /// of `jacobian`.
    #[getter]
    fn outputs(&self) -> Vec<String> {
        self.s.outputs.clone()
    }

    /// The parameters' case keys, the columns of `jacobian`.
    #[getter]
    fn parameters(&self) -> Vec<String> {
        self.s.parameters.iter().map(|p| p.key.clone()).collect()
    }

    /// How each parameter is taken: `value` (the key's number), `factor` (a factor on an
    /// expression, a table or per-vertex data, at 1) or `offset` (a constant added to a
    /// surface or height, at 0).
    #[getter]
    fn kinds(&self) -> Vec<&'static str> {
        self.s.parameters.iter().map(|p| p.kind.name()).collect()
    }

    /// The parameters' values in the case (1 for a factor, 0 for an offset).
    #[getter]
    fn parameter_values<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.cache.get(py, 0, || {
            owned1(py, self.s.parameters.iter().map(|p| p.value).collect())
        })
    }

    /// The outputs' values Q (one per output).
    #[getter]
    fn values<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.cache.get(py, 1, || owned1(py, self.s.values.clone()))
    }

    /// dQ/dp, outputs × parameters (the mean of the one-sided derivatives where they
    /// differ: see `nonsmooth`).
    #[getter]
    fn jacobian<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.cache.get(py, 2, || {
            owned2(py, self.s.derivative.clone(), self.n_parameters())
        })
    }

    /// The derivative in the direction +δp, outputs × parameters.
    #[getter]
    fn derivative_plus<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.cache.get(py, 3, || {
            owned2(py, self.s.derivative_plus.clone(), self.n_parameters())
        })
    }

    /// Minus the derivative in the direction −δp, outputs × parameters.
    #[getter]
    fn derivative_minus<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.cache.get(py, 4, || {
            owned2(py, self.s.derivative_minus.clone(), self.n_parameters())
        })
    }

    /// Where the one-sided derivatives differ (biactive vertices reach the output),
    /// outputs × parameters.
    #[getter]
    fn nonsmooth<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.cache.get(py, 5, || {
            owned2(py, self.s.nonsmooth.clone(), self.n_parameters())
        })
    }

    /// The elasticities (p/Q) dQ/dp, outputs × parameters (NaN for an offset, p = 0 or
    /// Q = 0).
    #[getter]
    fn elasticity<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.cache.get(py, 6, || {
            let np = self.n_parameters();
            let v = (0..self.s.outputs.len() * np)
                .map(|k| self.s.elasticity(k / np, k % np))
                .collect();
            owned2(py, v, np)
        })
    }

    /// The influence maps over the mesh's vertices (`dJ_dh`, `dsensor_NAME_dh`, ...): how
    /// much each vertex's soil stiffness matters for the output.
    #[getter]
    fn influence<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.cache.get(py, 7, || {
            let d = PyDict::new(py);
            for (name, v) in &self.s.influence {
                d.set_item(name, owned1(py, v.clone())?)?;
            }
            Ok(d.into_any())
        })
    }

    /// The number of biactive vertices (touching without force, to the certificate's
    /// accuracy), where the solution map has one-sided derivatives only.
    #[getter]
    fn biactive(&self) -> usize {
        self.s.biactive()
    }

    /// The biactive vertices (the mesh's numbering).
    #[getter]
    fn biactive_vertices(&self) -> Vec<u32> {
        self.s.biactive_vertices.clone()
    }

    /// How the derivatives were computed: `adjoint`, `tangent` or `one_sided`.
    #[getter]
    fn mode(&self) -> &'static str {
        self.s.mode.name()
    }

    /// Every linear solve (what, solver, iterations, residual, seconds).
    #[getter]
    fn solves<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_py(py, &self.s.solves)
    }

    /// The solve the derivatives were taken at.
    #[getter]
    fn result(&self, py: Python<'_>) -> Py<PyResult_> {
        self.result.clone_ref(py)
    }

    /// The columns of `rows`: those of `sensitivity.csv`, then `nonsmooth` and `kind`
    /// (the same as `biactive` and `parameter_kind`, under their earlier names).
    #[getter]
    fn columns(&self) -> Vec<&'static str> {
        memcontact::write::SENSITIVITY_COLUMNS
            .into_iter()
            .chain(EARLIER_COLUMNS)
            .collect()
    }

    /// One dict per output and parameter, as the rows of `sensitivity.csv` (None where
    /// the file's cell is empty).
    #[getter]
    fn rows<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let np = self.n_parameters();
        let list = PyList::empty(py);
        for o in 0..self.s.outputs.len() {
            for p in 0..np {
                let k = o * np + p;
                let row = PyDict::new(py);
                row.set_item("output", &self.s.outputs[o])?;
                row.set_item("parameter", &self.s.parameters[p].key)?;
                row.set_item("value", self.s.values[o])?;
                row.set_item("derivative", self.s.derivative[k])?;
                row.set_item("elasticity", cell(py, self.s.elasticity(o, p))?)?;
                let (plus, minus) = if self.s.nonsmooth[k] {
                    (self.s.derivative_plus[k], self.s.derivative_minus[k])
                } else {
                    (f64::NAN, f64::NAN)
                };
                row.set_item("derivative_plus", cell(py, plus)?)?;
                row.set_item("derivative_minus", cell(py, minus)?)?;
                row.set_item("biactive", i32::from(self.s.nonsmooth[k]))?;
                row.set_item("parameter_kind", self.s.parameters[p].kind.name())?;
                row.set_item("parameter_value", cell(py, self.s.parameters[p].value)?)?;
                row.set_item("nonsmooth", self.s.nonsmooth[k])?;
                row.set_item("kind", self.s.parameters[p].kind.name())?;
                list.append(row)?;
            }
        }
        Ok(list)
    }

    /// Writes the result set `memcontact solve` writes for a case with `[sensitivity]`
    /// into `directory`, atomically: the solve's files with the influence maps in
    /// `solution.vtu`, `sensitivity.csv`, the pictures (unless `pictures` is false) and
    /// `summary.json`. Returns the summary.
    #[pyo3(signature = (directory, force=false, vtu=None, pictures=true))]
    fn write<'py>(
        &self,
        py: Python<'py>,
        directory: PathBuf,
        force: bool,
        vtu: Option<&str>,
        pictures: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        let result = self.result.get();
        let summary = write_set(
            py,
            &directory,
            &self.label,
            &self.case,
            result,
            (force, vtu, pictures),
            Some(&self.s),
            None,
        )?;
        to_py(py, &summary)
    }

    /// The rows as a `pandas.DataFrame` (see `rows`).
    fn to_pandas<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        crate::convert::call_helper(slf.py(), "to_pandas", (slf,), None)
    }

    fn __repr__(&self) -> String {
        format!(
            "Sensitivities({} outputs × {} parameters, {}, {} biactive vertices)",
            self.s.outputs.len(),
            self.n_parameters(),
            self.s.mode.name(),
            self.s.biactive()
        )
    }
}

/// The write of a result set with the sensitivity's and the fit's files.
#[allow(clippy::too_many_arguments)]
fn write_set(
    py: Python<'_>,
    directory: &std::path::Path,
    label: &str,
    case: &Case,
    result: &PyResult_,
    (force, vtu, pictures): (bool, Option<&str>, bool),
    s: Option<&Sensitivities>,
    fit: Option<&FitResult>,
) -> PyResult<memcontact::Summary> {
    let vtu = vtu_format(vtu, case)?;
    crate::convert::detached(py, || -> memcontact::Result<_> {
        let outcome = result.outcome()?;
        let mut plots = write::plot_options(case, label);
        if !pictures {
            plots.plots.clear();
        }
        let options = WriteOptions {
            vtu,
            force,
            ..WriteOptions::new(label)
        };
        write::write_sensitivity_result(directory, &outcome, case, &options, &plots, s, fit)
    })
    .map_err(py_err)
}

/// A fit of a case's parameters to measured deflections (`fit.json`'s content), and the
/// solve at the fitted (or, without convergence, the best) parameters.
#[pyclass(name = "Fit", module = "memcontact._memcontact", frozen)]
pub struct PyFit {
    label: String,
    case: Case,
    fit: FitResult,
    sensitivities: Option<Sensitivities>,
    result: Py<PyResult_>,
    cache: Cache<6>,
}

/// Runs the fit of a case with `[fit]` with the GIL released (`memcontact::run::run_fit`).
#[pyfunction]
pub fn fit(py: Python<'_>, case: PyRef<'_, PyCase>) -> PyResult<PyFit> {
    let mut c = case.case.clone();
    let label = case.label.clone();
    drop(case);
    if c.fit.is_none() {
        return Err(PyValueError::new_err(
            "fit: the case has no [fit] section (give parameters= with their bounds)",
        ));
    }
    let cancel = memcontact::Cancel::new();
    c.settings.cancel = cancel.clone();
    let result_label = label.clone();
    let (fit, fitted_case, sensitivities, result) = interruptible(py, &cancel, move || {
        let started = Instant::now();
        let run = memcontact::run::run_fit(&c, &mut Silent)?;
        let mesh = PyMesh::new_from(run.outcome.discretization.user_hierarchy());
        let result = PyResult_::new(
            result_label,
            run.fitted_case.clone(),
            mesh,
            run.outcome,
            started,
        );
        Ok((run.fit, run.fitted_case, run.sensitivities, result))
    })?;
    Ok(PyFit {
        label,
        case: fitted_case,
        fit,
        sensitivities,
        result: Py::new(py, result)?,
        cache: Cache::default(),
    })
}

impl PyFit {
    fn n(&self) -> usize {
        self.fit.parameters.len()
    }
}

#[pymethods]
impl PyFit {
    /// The fitted case keys, in order.
    #[getter]
    fn names(&self) -> Vec<String> {
        self.fit.parameters.iter().map(|p| p.key.clone()).collect()
    }

    /// The fitted values, key → value.
    #[getter]
    fn parameters<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for p in &self.fit.parameters {
            d.set_item(&p.key, p.value)?;
        }
        Ok(d)
    }

    /// The fitted values, in the order of `names`.
    #[getter]
    fn values<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.cache.get(py, 0, || {
            owned1(py, self.fit.parameters.iter().map(|p| p.value).collect())
        })
    }

    /// The start values (the case's own).
    #[getter]
    fn start<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.cache.get(py, 1, || {
            owned1(py, self.fit.parameters.iter().map(|p| p.start).collect())
        })
    }

    /// The standard errors, from σ² (JᵀWJ)⁻¹ (σ² estimated from the residuals when the
    /// measurements give no σ).
    #[getter]
    fn std_errors<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.cache.get(py, 2, || {
            owned1(
                py,
                self.fit.parameters.iter().map(|p| p.std_error).collect(),
            )
        })
    }

    /// The correlation matrix of the fitted parameters.
    #[getter]
    fn correlation<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.cache.get(py, 3, || {
            owned2(py, self.fit.statistics.correlation.clone(), self.n())
        })
    }

    /// The singular values of the scaled Jacobian (a small one: a combination of the
    /// parameters the measurements cannot tell).
    #[getter]
    fn singular_values<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.cache.get(py, 4, || {
            owned1(py, self.fit.statistics.singular_values.clone())
        })
    }

    /// The bounds, one `[min, max]` row per parameter.
    #[getter]
    fn bounds<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.cache.get(py, 5, || {
            owned2(
                py,
                self.fit.parameters.iter().flat_map(|p| p.bounds).collect(),
                2,
            )
        })
    }

    /// The condition number of the scaled Jacobian.
    #[getter]
    fn condition_number(&self) -> f64 {
        self.fit.statistics.condition_number
    }

    /// The root-mean-square of the weighted residuals (Q − m)/σ.
    #[getter]
    fn rms(&self) -> f64 {
        self.fit.rms
    }

    /// Accepted iterations.
    #[getter]
    fn iterations(&self) -> usize {
        self.fit.iterations
    }

    /// Forward solves, trial steps included.
    #[getter]
    fn solves(&self) -> usize {
        self.fit.solves
    }

    /// Whether the fit converged.
    #[getter]
    fn converged(&self) -> bool {
        self.fit.converged
    }

    /// Why it stopped (`step`, `gradient`, `residual`, `max_iterations`, `stalled`, ...).
    #[getter]
    fn stop(&self) -> &'static str {
        self.fit.stop.name()
    }

    /// The identifiability warning, when the measurements cannot determine the
    /// parameters (None otherwise).
    #[getter]
    fn warning(&self) -> Option<String> {
        self.fit.statistics.warning.clone()
    }

    /// The measurements and the deflections computed there (name, at, measured, sigma,
    /// computed).
    #[getter]
    fn measurements<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_py(py, &self.fit.measurements)
    }

    /// `fit.json`'s content as a dict.
    #[getter]
    fn summary<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_py(py, &self.fit)
    }

    /// The solve at the fitted (or best) parameters.
    #[getter]
    fn result(&self, py: Python<'_>) -> Py<PyResult_> {
        self.result.clone_ref(py)
    }

    /// The case with the fitted values.
    #[getter]
    fn case(&self) -> PyCase {
        PyCase {
            case: self.case.clone(),
            label: self.label.clone(),
        }
    }

    /// The columns of `rows`: those of `fit.csv` (iteration, rms, step, damping, solves,
    /// then each parameter's key).
    #[getter]
    fn columns(&self) -> Vec<String> {
        FIT_COLUMNS
            .iter()
            .map(|c| c.to_string())
            .chain(self.fit.parameters.iter().map(|p| p.key.clone()))
            .collect()
    }

    /// One dict per accepted iterate, as the rows of `fit.csv`.
    #[getter]
    fn rows<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let list = PyList::empty(py);
        for h in &self.fit.history {
            let row = PyDict::new(py);
            row.set_item("iteration", h.iteration)?;
            row.set_item("rms", h.rms)?;
            row.set_item("step", h.step)?;
            row.set_item("damping", h.damping)?;
            row.set_item("solves", h.solves)?;
            for (p, v) in self.fit.parameters.iter().zip(&h.parameters) {
                row.set_item(&p.key, *v)?;
            }
            list.append(row)?;
        }
        Ok(list)
    }

    /// Writes the result set `memcontact solve` writes for a case with `[fit]` into
    /// `directory`, atomically: the solve at the fitted parameters, `fit.json`,
    /// `fit.csv`, `fit.png` and the other pictures (unless `pictures` is false), and
    /// `summary.json`. Returns the summary.
    #[pyo3(signature = (directory, force=false, vtu=None, pictures=true))]
    fn write<'py>(
        &self,
        py: Python<'py>,
        directory: PathBuf,
        force: bool,
        vtu: Option<&str>,
        pictures: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        let summary = write_set(
            py,
            &directory,
            &self.label,
            &self.case,
            self.result.get(),
            (force, vtu, pictures),
            self.sensitivities.as_ref(),
            Some(&self.fit),
        )?;
        to_py(py, &summary)
    }

    /// The iterates as a `pandas.DataFrame` (see `rows`).
    fn to_pandas<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        crate::convert::call_helper(slf.py(), "to_pandas", (slf,), None)
    }

    fn __repr__(&self) -> String {
        format!(
            "Fit({} parameters, {}, rms {:.3e}, {} iterations, {} solves{})",
            self.n(),
            if self.fit.converged {
                "converged".to_string()
            } else {
                format!("not converged ({})", self.fit.stop.name())
            },
            self.fit.rms,
            self.fit.iterations,
            self.fit.solves,
            if self.fit.statistics.warning.is_some() {
                ", not identifiable"
            } else {
                ""
            }
        )
    }
}

/// A fit's model for an optimiser of one's own: the weighted residuals (Q(p) − m)/σ of the
/// measured deflections and their exact Jacobian in the parameters p (physical units),
/// one warm-started solve per new p.
#[pyclass(name = "FitProblem", module = "memcontact._memcontact", frozen)]
pub struct PyFitProblem {
    problem: Mutex<FitProblem>,
    names: Vec<String>,
    start: Vec<f64>,
    bounds: Vec<[f64; 2]>,
    measurements: Vec<String>,
}

/// The model of a case with `[fit]` (mesh built and assembled, measurements located,
/// nothing solved yet).
#[pyfunction]
pub fn fit_problem(py: Python<'_>, case: PyRef<'_, PyCase>) -> PyResult<PyFitProblem> {
    let c = case.case.clone();
    drop(case);
    let problem =
        crate::convert::detached(py, || FitProblem::new(&c, &mut Silent)).map_err(py_err)?;
    Ok(PyFitProblem {
        names: problem.parameter_names(),
        start: problem.start(),
        bounds: problem.bounds(),
        measurements: problem.measurement_names(),
        problem: Mutex::new(problem),
    })
}

impl PyFitProblem {
    fn at(&self, p: &[f64]) -> PyResult<()> {
        if p.len() != self.names.len() {
            return Err(PyValueError::new_err(format!(
                "p: {} values for the {} parameters ({})",
                p.len(),
                self.names.len(),
                self.names.join(", ")
            )));
        }
        if let Some((k, v)) = p.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(PyValueError::new_err(format!(
                "p: {} = {v} is not a finite number",
                self.names[k]
            )));
        }
        Ok(())
    }

    fn with<T: Send>(
        &self,
        py: Python<'_>,
        f: impl FnOnce(&mut FitProblem) -> memcontact::Result<T> + Send,
    ) -> PyResult<T> {
        crate::convert::detached(py, || {
            let mut problem = self
                .problem
                .lock()
                .map_err(|_| Error::Data("the fit problem is unusable after a panic".into()))?;
            f(&mut problem)
        })
        .map_err(py_err)
    }
}

#[pymethods]
impl PyFitProblem {
    /// The fitted case keys, in order.
    #[getter]
    fn names(&self) -> Vec<String> {
        self.names.clone()
    }

    /// The start: the case's values.
    #[getter]
    fn x0<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        owned1(py, self.start.clone())
    }

    /// The bounds as `(lower, upper)` arrays, the form `scipy.optimize.least_squares`
    /// takes.
    #[getter]
    fn bounds<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
        Ok((
            owned1(py, self.bounds.iter().map(|b| b[0]).collect())?,
            owned1(py, self.bounds.iter().map(|b| b[1]).collect())?,
        ))
    }

    /// The measured sensors' names (the rows of the residuals).
    #[getter]
    fn measurements(&self) -> Vec<String> {
        self.measurements.clone()
    }

    /// The forward solves done so far.
    #[getter]
    fn solves(&self) -> PyResult<usize> {
        Ok(self
            .problem
            .lock()
            .map_err(|_| PyValueError::new_err("the fit problem is unusable after a panic"))?
            .solves())
    }

    /// The weighted residuals (Q(p) − m)/σ at `p` (one solve unless `p` is where the
    /// last solve was).
    fn residuals<'py>(&self, py: Python<'py>, p: Vec<f64>) -> PyResult<Bound<'py, PyAny>> {
        self.at(&p)?;
        let r = self.with(py, |fp| fp.residuals(&p))?;
        owned1(py, r)
    }

    /// The Jacobian of the residuals in p, measurements × parameters (exact, by tangent
    /// solves on the solve at `p`).
    fn jacobian<'py>(&self, py: Python<'py>, p: Vec<f64>) -> PyResult<Bound<'py, PyAny>> {
        self.at(&p)?;
        let n = self.names.len();
        let (_, j) = self.with(py, |fp| fp.residuals_and_jacobian(&p))?;
        owned2(py, j, n)
    }

    /// Both at once: `(residuals, jacobian)`.
    fn residuals_and_jacobian<'py>(
        &self,
        py: Python<'py>,
        p: Vec<f64>,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
        self.at(&p)?;
        let n = self.names.len();
        let (r, j) = self.with(py, |fp| fp.residuals_and_jacobian(&p))?;
        Ok((owned1(py, r)?, owned2(py, j, n)?))
    }

    fn __repr__(&self) -> String {
        format!(
            "FitProblem({} parameters: {}; {} measurements)",
            self.names.len(),
            self.names.join(", "),
            self.measurements.len()
        )
    }
}
