//! Conversions between Python values and the library's serde values, and between the
//! library's errors and Python exceptions.

use memcontact::Error;
use pyo3::exceptions::{PyFileNotFoundError, PyOSError, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};

/// The Python exception for a library error: bad data (a case, a mesh, an expression, a
/// file that does not parse) is a `ValueError`, a missing file `FileNotFoundError`, an
/// input/output failure `OSError`, anything the solver reports `RuntimeError`.
pub fn py_err(e: Error) -> PyErr {
    match &e {
        Error::Io { source, .. } if source.kind() == std::io::ErrorKind::NotFound => {
            PyFileNotFoundError::new_err(e.to_string())
        }
        Error::Io { .. } => PyOSError::new_err(e.to_string()),
        Error::File { path, .. } if !path.exists() => PyFileNotFoundError::new_err(e.to_string()),
        Error::Solver { .. } => PyRuntimeError::new_err(e.to_string()),
        _ => PyValueError::new_err(e.to_string()),
    }
}

/// A refused case given as a dict: `key: message` (the line of the TOML text it was turned
/// into means nothing to the caller).
pub fn dict_case_err(e: Error) -> PyErr {
    match e {
        Error::Case { key, message, .. } => PyValueError::new_err(if key.is_empty() {
            message
        } else {
            format!("{key}: {message}")
        }),
        other => py_err(other),
    }
}

/// The dotted key of `part` below `key`.
fn join(key: &str, part: &str) -> String {
    if key.is_empty() {
        part.to_string()
    } else {
        format!("{key}.{part}")
    }
}

/// A Python value (dicts, lists, tuples, numbers, strings, booleans, NumPy arrays and
/// scalars, paths) as a TOML value. `key` names the value in errors.
pub fn to_toml(obj: &Bound<'_, PyAny>, key: &str) -> PyResult<toml::Value> {
    to_toml_at(obj, key, 0)
}

/// How deeply a case's values may nest (a case file nests three or four levels; deeper
/// values would only exhaust the stack).
const MAX_DEPTH: usize = 32;

fn to_toml_at(obj: &Bound<'_, PyAny>, key: &str, depth: usize) -> PyResult<toml::Value> {
    let bad = |what: String| PyValueError::new_err(format!("{}{what}", prefix(key)));
    if depth > MAX_DEPTH {
        return Err(bad(format!(
            "the value nests more than {MAX_DEPTH} levels of lists and dicts"
        )));
    }
    let to_toml = |v: &Bound<'_, PyAny>, k: &str| to_toml_at(v, k, depth + 1);
    if obj.is_instance_of::<PyBool>() {
        return Ok(toml::Value::Boolean(obj.extract::<bool>()?));
    }
    if obj.is_instance_of::<PyInt>() {
        return match obj.extract::<i64>() {
            Ok(v) => Ok(toml::Value::Integer(v)),
            Err(_) => Err(bad(format!("the integer {obj} is too large"))),
        };
    }
    if obj.is_instance_of::<PyFloat>() {
        return Ok(toml::Value::Float(obj.extract::<f64>()?));
    }
    if obj.is_instance_of::<PyString>() {
        return Ok(toml::Value::String(obj.extract::<String>()?));
    }
    if let Ok(d) = obj.cast::<PyDict>() {
        let mut table = toml::Table::new();
        for (k, v) in d.iter() {
            // Region tables may be keyed by numeric tags.
            let name = if k.is_instance_of::<PyString>() {
                k.extract::<String>()?
            } else if k.is_instance_of::<PyInt>() && !k.is_instance_of::<PyBool>() {
                k.str()?.to_string()
            } else {
                return Err(bad(format!(
                    "keys must be strings, got {}",
                    k.get_type().name()?
                )));
            };
            let value = to_toml(&v, &join(key, &name))?;
            table.insert(name, value);
        }
        return Ok(toml::Value::Table(table));
    }
    if obj.is_none() {
        return Err(bad(
            "None is not a value (leave the key out to get its default)".into(),
        ));
    }
    if obj.is_instance_of::<PyList>() || obj.is_instance_of::<PyTuple>() {
        let mut items = Vec::new();
        for (i, v) in obj.try_iter()?.enumerate() {
            items.push(to_toml(&v?, &format!("{key}[{i}]"))?);
        }
        return Ok(toml::Value::Array(items));
    }
    // NumPy arrays and scalars: their Python equivalents.
    if obj.hasattr("tolist")? && obj.hasattr("dtype")? {
        let plain = obj.call_method0("tolist")?;
        return to_toml(&plain, key);
    }
    // The case file's sections as dataclasses (`memcontact.Membrane`, ...): their dicts.
    if obj.hasattr("__dataclass_fields__")? && obj.hasattr("to_dict")? {
        let plain = obj.call_method0("to_dict")?;
        if plain.is_instance_of::<PyDict>() {
            return to_toml(&plain, key);
        }
    }
    // Paths.
    if obj.hasattr("__fspath__")? {
        let text = obj.call_method0("__fspath__")?;
        return to_toml(&text, key);
    }
    Err(bad(format!(
        "a {} is not a case value (use numbers, strings, lists and dicts)",
        obj.get_type().name()?
    )))
}

fn prefix(key: &str) -> String {
    if key.is_empty() {
        String::new()
    } else {
        format!("{key}: ")
    }
}

/// A JSON value as the equivalent Python value (dicts, lists, floats, ints, strings, None).
pub fn json_to_py<'py>(py: Python<'py>, v: &serde_json::Value) -> PyResult<Bound<'py, PyAny>> {
    use serde_json::Value;
    Ok(match v {
        Value::Null => py.None().into_bound(py),
        Value::Bool(b) => PyBool::new(py, *b).to_owned().into_any(),
        Value::Number(n) => {
            if let Some(i) = n.as_i64() {
                i.into_pyobject(py)?.into_any()
            } else if let Some(u) = n.as_u64() {
                u.into_pyobject(py)?.into_any()
            } else {
                n.as_f64().unwrap_or(f64::NAN).into_pyobject(py)?.into_any()
            }
        }
        Value::String(s) => PyString::new(py, s).into_any(),
        Value::Array(items) => {
            let list = PyList::empty(py);
            for item in items {
                list.append(json_to_py(py, item)?)?;
            }
            list.into_any()
        }
        Value::Object(map) => {
            let dict = PyDict::new(py);
            for (k, item) in map {
                dict.set_item(k, json_to_py(py, item)?)?;
            }
            dict.into_any()
        }
    })
}

/// A serde value as a Python value (through JSON; non-finite floats become None, as JSON
/// has no NaN).
pub fn to_py<'py, T: serde::Serialize>(py: Python<'py>, value: &T) -> PyResult<Bound<'py, PyAny>> {
    let v = serde_json::to_value(value)
        .map_err(|e| PyValueError::new_err(format!("cannot convert to Python: {e}")))?;
    json_to_py(py, &v)
}

/// Runs `f` with the GIL released on the library's worker threads (the pool of this
/// process: a process forked from one that has solved builds its own).
pub fn detached<T: Send>(py: Python<'_>, f: impl FnOnce() -> T + Send) -> T {
    py.detach(|| memcontact::on_workers(f))
}

/// Runs `f` like [`detached`] while this thread checks Python's signals every 50 ms: on
/// Ctrl-C (a KeyboardInterrupt, or whatever the signal handlers raise) `cancel` is set, the
/// run stops within its iteration, and the exception is raised.
pub fn interruptible<T: Send>(
    py: Python<'_>,
    cancel: &memcontact::Cancel,
    f: impl FnOnce() -> memcontact::Result<T> + Send,
) -> PyResult<T> {
    use std::sync::mpsc;
    use std::time::Duration;
    std::thread::scope(|s| {
        let (tx, rx) = mpsc::channel();
        s.spawn(move || {
            let _ = tx.send(memcontact::on_workers(f));
        });
        let mut rx = rx;
        loop {
            let (got, back) = py.detach(move || (rx.recv_timeout(Duration::from_millis(50)), rx));
            rx = back;
            match got {
                Ok(result) => return result.map_err(py_err),
                Err(mpsc::RecvTimeoutError::Disconnected) => {
                    return Err(pyo3::exceptions::PyRuntimeError::new_err(
                        "the run's thread ended without an answer",
                    ))
                }
                Err(mpsc::RecvTimeoutError::Timeout) => {}
            }
            if let Err(e) = py.check_signals() {
                cancel.cancel();
                // The run stops at its next check; its error is the interruption.
                let _ = py.detach(move || rx.recv());
                return Err(e);
            }
        }
    })
}

/// Calls `name` of the pure-Python helpers (`memcontact._notebook`: plotting, tables,
/// meshio, pyvista, scipy), which import their optional packages when called.
pub fn call_helper<'py>(
    py: Python<'py>,
    name: &str,
    args: impl pyo3::call::PyCallArgs<'py>,
    kwargs: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyAny>> {
    py.import("memcontact._notebook")?
        .getattr(name)?
        .call(args, kwargs)
}

/// A count given in Python (an int, or a NumPy integer; not a bool): a `TypeError` for
/// another type, a `ValueError` naming `what` for a negative or too large one.
pub fn count(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<usize> {
    use pyo3::exceptions::PyTypeError;
    if obj.is_instance_of::<PyBool>() || !obj.hasattr("__index__")? {
        return Err(PyTypeError::new_err(format!(
            "{what}: an integer is needed, got a {}",
            obj.get_type().name()?
        )));
    }
    let index = obj.call_method0("__index__")?;
    match index.extract::<i64>() {
        Ok(v) if v >= 0 => usize::try_from(v)
            .map_err(|_| PyValueError::new_err(format!("{what}: {v} is too large"))),
        Ok(v) => Err(PyValueError::new_err(format!(
            "{what}: must not be negative, got {v}"
        ))),
        Err(_) => Err(PyValueError::new_err(format!(
            "{what}: {index} is too large"
        ))),
    }
}
