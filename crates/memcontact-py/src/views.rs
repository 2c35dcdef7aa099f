//! Read-only NumPy arrays of data the Rust side owns: views of the immutable vectors of a
//! result or a mesh (no copy), or arrays converted once (another dtype); either way made
//! once per object, cached, and not writeable (writing raises `ValueError`).

use numpy::ndarray::{ArrayView1, ArrayView2};
use numpy::{Element, PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::PyDict;
use std::any::Any;

/// What keeps the memory of borrowed arrays alive: the `base` of every view, holding a
/// shared reference to the immutable data (never the Python object whose property made
/// the view, which would be a reference cycle through its cache).
#[pyclass(name = "_Owner", module = "memcontact._memcontact", frozen)]
pub struct Owner {
    _keep: Box<dyn Any + Send + Sync>,
}

/// The owner of views into `keep` (an `Arc` of immutable data).
pub fn owner<'py>(py: Python<'py>, keep: impl Any + Send + Sync) -> PyResult<Bound<'py, PyAny>> {
    Ok(Bound::new(
        py,
        Owner {
            _keep: Box::new(keep),
        },
    )?
    .into_any())
}

/// `array` made read-only (numpy refuses to make it writeable again: it does not own its
/// memory, or its owner is not a writeable buffer).
pub fn read_only<'py>(array: Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
    let kwargs = PyDict::new(array.py());
    kwargs.set_item("write", false)?;
    array.call_method("setflags", (), Some(&kwargs))?;
    Ok(array)
}

/// A read-only 1-D view of `data`, kept alive by `owner`.
///
/// # Safety
/// `data` must stay at its address, unchanged, as long as `owner` lives (it is part of
/// the immutable value `owner` holds).
pub unsafe fn view1<'py, T: Element>(
    data: &[T],
    owner: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyAny>> {
    let view = ArrayView1::from(data);
    // SAFETY: the caller's promise.
    let a = unsafe { PyArray1::borrow_from_array(&view, owner.clone()) };
    read_only(a.into_any())
}

/// A read-only 2-D view (rows of `cols` values) of `data`, kept alive by `owner`.
///
/// # Safety
/// As [`view1`]; `data.len()` is a multiple of `cols`.
pub unsafe fn view2<'py, T: Element>(
    data: &[T],
    cols: usize,
    owner: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyAny>> {
    let rows = data.len().checked_div(cols).unwrap_or(0);
    let view = ArrayView2::from_shape((rows, cols), data)
        .map_err(|e| pyo3::exceptions::PyValueError::new_err(format!("view: {e}")))?;
    // SAFETY: the caller's promise.
    let a = unsafe { PyArray2::borrow_from_array(&view, owner.clone()) };
    read_only(a.into_any())
}

/// A read-only array that owns its values (converted once from the Rust data).
pub fn owned1<'py, T: Element>(py: Python<'py>, v: Vec<T>) -> PyResult<Bound<'py, PyAny>> {
    read_only(PyArray1::from_vec(py, v).into_any())
}

/// A read-only (rows × `cols`) array that owns its values.
pub fn owned2<'py, T: Element>(
    py: Python<'py>,
    v: Vec<T>,
    cols: usize,
) -> PyResult<Bound<'py, PyAny>> {
    let rows = v.len().checked_div(cols).unwrap_or(0);
    let a = numpy::ndarray::Array2::from_shape_vec((rows, cols), v)
        .map_err(|e| pyo3::exceptions::PyValueError::new_err(format!("array: {e}")))?;
    read_only(PyArray2::from_owned_array(py, a).into_any())
}

/// A cache of one Python object per slot, made on first access.
pub struct Cache<const N: usize> {
    slots: [PyOnceLock<Py<PyAny>>; N],
}

impl<const N: usize> Default for Cache<N> {
    fn default() -> Self {
        Cache {
            slots: std::array::from_fn(|_| PyOnceLock::new()),
        }
    }
}

impl<const N: usize> Cache<N> {
    /// The object of `slot`, made by `make` the first time.
    pub fn get<'py>(
        &self,
        py: Python<'py>,
        slot: usize,
        make: impl FnOnce() -> PyResult<Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let obj = self.slots[slot].get_or_try_init(py, || make().map(Bound::unbind))?;
        Ok(obj.bind(py).clone())
    }
}
