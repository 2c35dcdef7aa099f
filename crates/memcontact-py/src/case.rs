//! `Case`: a case file's content (mesh, membrane, obstacle, solver, output, exact), from a
//! file or a dict, with the same schema and the same errors.

use crate::convert::{dict_case_err, py_err, to_py, to_toml};
use memcontact::Case;
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};
use std::path::PathBuf;

/// A case: the problem (mesh, membrane, obstacle), the solver settings, the output options
/// and the exact solution, exactly as a case file holds them. Immutable.
#[pyclass(name = "Case", module = "memcontact._memcontact", frozen)]
#[derive(Clone)]
pub struct PyCase {
    pub case: Case,
    /// The case's name in `summary.json` (its file, or what the caller chose).
    pub label: String,
}

/// A dict in the case file's schema as a case (the dict goes through TOML, so every value
/// and error is the case file's).
pub fn case_from_dict(data: &Bound<'_, PyAny>) -> PyResult<Case> {
    if !data.is_instance_of::<PyDict>() {
        return Err(PyTypeError::new_err(format!(
            "a case is a dict with the sections mesh, membrane, obstacle (and optionally \
             solver, output, exact), got a {}",
            data.get_type().name()?
        )));
    }
    let value = to_toml(data, "")?;
    let text = toml::to_string(&value)
        .map_err(|e| PyValueError::new_err(format!("cannot read the case: {e}")))?;
    Case::from_toml_str(&text, None).map_err(dict_case_err)
}

/// The TOML text of a Python value (for `--set`-style overrides).
#[pyfunction]
pub fn _toml_value(value: &Bound<'_, PyAny>) -> PyResult<String> {
    Ok(to_toml(value, "")?.to_string())
}

#[pymethods]
impl PyCase {
    /// Case(data, label="case")
    ///
    /// A case from a dict with the case file's sections (`mesh`, `membrane`, `obstacle`,
    /// optionally `solver`, `output`, `exact`) and keys. Unknown keys and bad values raise
    /// `ValueError` naming the key, before any work. A relative mesh `file` is relative to
    /// the current directory.
    #[new]
    #[pyo3(signature = (data, label=None))]
    fn py_new(data: &Bound<'_, PyAny>, label: Option<String>) -> PyResult<PyCase> {
        if let Ok(c) = data.cast::<PyCase>() {
            let c = c.get();
            return Ok(PyCase {
                case: c.case.clone(),
                label: label.unwrap_or_else(|| c.label.clone()),
            });
        }
        Ok(PyCase {
            case: case_from_dict(data)?,
            label: label.unwrap_or_else(|| "case".into()),
        })
    }

    /// Reads a case file, applying `key=value` overrides (dotted keys, TOML values) first.
    #[staticmethod]
    #[pyo3(signature = (path, overrides=Vec::new()))]
    fn load(py: Python<'_>, path: PathBuf, overrides: Vec<String>) -> PyResult<PyCase> {
        let case = py
            .detach(|| Case::load(&path, &overrides))
            .map_err(py_err)?;
        Ok(PyCase {
            case,
            label: path.display().to_string(),
        })
    }

    /// A case from TOML text (a case file's content); relative mesh paths are relative to
    /// the current directory.
    #[staticmethod]
    #[pyo3(signature = (text, label=None))]
    fn from_toml(text: &str, label: Option<String>) -> PyResult<PyCase> {
        Ok(PyCase {
            case: Case::from_toml_str(text, None).map_err(py_err)?,
            label: label.unwrap_or_else(|| "case".into()),
        })
    }

    /// The case as a dict (every section, defaults filled in); `Case(case.to_dict())`
    /// is an equal case.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_py(py, &self.case)
    }

    /// The case as TOML text (a case file).
    fn to_toml(&self) -> PyResult<String> {
        self.case.to_toml_string().map_err(py_err)
    }

    /// The case's name in `summary.json`.
    #[getter]
    fn label(&self) -> String {
        self.label.clone()
    }

    /// A copy with another label.
    fn with_label(&self, label: String) -> PyCase {
        PyCase {
            case: self.case.clone(),
            label,
        }
    }

    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        other
            .cast::<PyCase>()
            .is_ok_and(|o| o.get().case == self.case)
    }

    fn __repr__(&self) -> String {
        format!(
            "Case({:?}, mesh: {}, method: {})",
            self.label,
            self.case.problem.mesh.kind(),
            self.case.settings.method.name()
        )
    }

    /// Pickling: the TOML text and the label.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        let cls = py.import("memcontact._memcontact")?.getattr("Case")?;
        let from_toml = cls.getattr("from_toml")?;
        let args = (self.to_toml()?, self.label.clone()).into_pyobject(py)?;
        PyTuple::new(py, [from_toml, args.into_any()])
    }

    /// A deterministic token for Dask (the case's TOML text and label).
    fn __dask_tokenize__(&self) -> PyResult<(String, String)> {
        Ok((self.to_toml()?, self.label.clone()))
    }
}
