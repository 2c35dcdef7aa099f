//! `Case`: a case file's content (mesh, membrane, obstacle, solver, output, exact), from a
//! file or a dict, with the same schema and the same errors.

use crate::convert::{dict_case_err, py_err, to_py, to_toml};
use memcontact::field::{Field, Stiffness};
use memcontact::mesh::refine::Hierarchy;
use memcontact::problem::{GivenMesh, MeshSource};
use memcontact::Case;
use numpy::PyReadonlyArray1;
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};
use std::path::PathBuf;
use std::sync::Arc;

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

/// The keys of a case whose data may be given as NumPy arrays of one value per vertex.
const NODAL_KEYS: [(&str, &str); 6] = [
    ("membrane", "load"),
    ("obstacle", "shape"),
    ("obstacle", "stiffness"),
    ("boundary", "height"),
    ("lower", "shape"),
    ("lower", "stiffness"),
];

/// The case a dict describes on a mesh given as data (`MeshSource::Given`): the dict has
/// the sections of a case file but `mesh`. NumPy arrays at the keys of [`NODAL_KEYS`] are
/// the data's values at the mesh's vertices (`Field::Nodal`), taken as they are instead of
/// going through the case file's text.
pub fn case_on_mesh(data: &Bound<'_, PyDict>, mesh: &Arc<Hierarchy>) -> PyResult<Case> {
    if data.contains("mesh")? {
        return Err(PyValueError::new_err(
            "mesh: the mesh is given as the mesh argument, not in the case's data",
        ));
    }
    let mut nodal: Vec<(&str, &str, Arc<[f64]>)> = Vec::new();
    let mut value = to_toml(data, "")?;
    let table = value.as_table_mut().expect("a dict is a table");
    for (section, key) in NODAL_KEYS {
        let Some(array) = data
            .get_item(section)?
            .and_then(|s| s.cast_into::<PyDict>().ok())
            .and_then(|s| s.get_item(key).ok().flatten())
            .filter(|v| v.hasattr("dtype").unwrap_or(false))
        else {
            continue;
        };
        let values: PyReadonlyArray1<'_, f64> = array.extract().map_err(|_| {
            PyValueError::new_err(format!(
                "{section}.{key}: nodal values must be a one-dimensional float64 array"
            ))
        })?;
        nodal.push((section, key, values.as_array().iter().copied().collect()));
        // The schema's check of the key sees a number; the values are set below.
        if let Some(toml::Value::Table(s)) = table.get_mut(section) {
            s.insert(key.into(), toml::Value::Float(0.0));
        }
    }
    let given = GivenMesh::shared(mesh.clone());
    let mut mesh_table = toml::Table::new();
    mesh_table.insert(
        "given".into(),
        toml::Value::String(given.description.clone()),
    );
    table.insert("mesh".into(), toml::Value::Table(mesh_table));
    let text = toml::to_string(&value)
        .map_err(|e| PyValueError::new_err(format!("cannot read the case: {e}")))?;
    let mut case = Case::from_toml_str(&text, None).map_err(dict_case_err)?;
    case.problem.mesh.source = MeshSource::Given(given);
    for (section, key, values) in nodal {
        let field = Field::Nodal(values);
        let p = &mut case.problem;
        match (section, key, p.lower.as_mut()) {
            ("membrane", "load", _) => p.membrane.load = field,
            ("obstacle", "shape", _) => p.obstacle.shape = field,
            ("obstacle", "stiffness", _) => p.obstacle.stiffness = Stiffness::Elastic(field),
            ("boundary", "height", _) => p.boundary.height = field,
            ("lower", "shape", Some(low)) => low.shape = field,
            ("lower", "stiffness", Some(low)) => low.stiffness = Stiffness::Elastic(field),
            _ => unreachable!("NODAL_KEYS lists the keys matched here"),
        }
    }
    case.validate().map_err(|e| dict_case_err(e.into_error()))?;
    Ok(case)
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
        let case =
            crate::convert::detached(py, || Case::load(&path, &overrides)).map_err(py_err)?;
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
