//! `Result`: the outcome of one solve as NumPy arrays and dicts, writable as the command
//! line tool's result set, picklable.

use crate::case::PyCase;
use crate::convert::{py_err, to_py};
use crate::mesh::{hierarchy_from_state, mesh_state, PyMesh};
use crate::views::{self, Cache};
use memcontact::case::VtuFormat;
use memcontact::discretization::Phase;
use memcontact::outcome::fields::{LowerFields, NodalFields};
use memcontact::outcome::{SparseRows, System, SystemBody};
use memcontact::run::step_discretization;
use memcontact::solve::Certificate;
use memcontact::solve::{Choice, Fallback, IterationRecord, Multipliers, Silent};
use memcontact::write::PlotKind;
use memcontact::write::{input_hash, new_run_id, WriteOptions};
use memcontact::write::{plot_options, write_result};
use memcontact::{Case, Discretization, Method, Outcome, Report, Status, Summary};
use numpy::{PyArray1, PyReadonlyArray1};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyTuple};
use serde::{Deserialize, Serialize};
use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// What a result holds (shared, immutable).
pub struct ResultData {
    /// The case's label.
    pub label: String,
    /// The case solved (for a mesh given in Python: its data on that mesh).
    pub case: Case,
    /// The solved mesh and its levels.
    pub mesh: PyMesh,
    /// The vertex fields.
    pub fields: NodalFields,
    /// The scalars of `summary.json` (without the file records).
    pub summary: Summary,
    /// Status, method, certificate, history, times, and U.
    pub report: Report,
    /// Warnings from reading the mesh.
    pub warnings: Vec<String>,
    /// Seconds from the start of the run to the end of the solve.
    pub seconds: f64,
    /// For a step of a sweep or a load case: its index among the case's steps (the model
    /// is the step's, not the base case's).
    pub step: Option<usize>,
    /// For the last step of an adaptive loop: η_T per triangle (energy-norm units).
    pub estimator: Option<Vec<f64>>,
}

/// The result of a solve: the vertex fields as NumPy arrays, the status, the report and
/// the summary. Immutable; pickles (the fields and the iterate travel, the assembled
/// matrices are rebuilt when `write` needs them).
#[pyclass(name = "Result", module = "memcontact._memcontact", frozen)]
pub struct PyResult_ {
    data: Arc<ResultData>,
    /// The discretisation and report, kept for `write` (rebuilt after unpickling).
    outcome: Mutex<Option<Arc<Outcome>>>,
    /// The arrays and the mesh handed out (made once, read-only).
    cache: Cache<{ Slot::COUNT }>,
}

/// What a result hands out once and caches.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Slot {
    U,
    Phi,
    Penetration,
    Pressure,
    ContactForce,
    State,
    PhiLow,
    PenetrationLow,
    PressureLow,
    ContactForceLow,
    StateLow,
    Estimator,
    Mesh,
    Png,
}

impl Slot {
    const COUNT: usize = 14;
}

impl PyResult_ {
    /// The result of `outcome`, solved from `case` on `mesh`.
    pub fn new(
        label: String,
        case: Case,
        mesh: PyMesh,
        outcome: Outcome,
        started: Instant,
    ) -> PyResult_ {
        Self::with_estimator(label, case, mesh, outcome, started, None)
    }

    /// [`PyResult_::new`] with the error estimator η_T per triangle (an adaptive loop's
    /// last step).
    pub fn with_estimator(
        label: String,
        case: Case,
        mesh: PyMesh,
        outcome: Outcome,
        started: Instant,
        estimator: Option<Vec<f64>>,
    ) -> PyResult_ {
        let seconds = started.elapsed().as_secs_f64();
        let mut data = Self::data_of(label, case, mesh, &outcome, seconds, None);
        data.estimator = estimator;
        PyResult_ {
            data: Arc::new(data),
            outcome: Mutex::new(Some(Arc::new(outcome))),
            cache: Cache::default(),
        }
    }

    /// The result of step `index` of a sweep of `case`, solved as `outcome` in `seconds`
    /// (`label` is the step's label). The outcome is not kept: `write` rebuilds the step's
    /// model on the mesh when it needs it.
    pub fn of_step(
        label: String,
        case: Case,
        mesh: PyMesh,
        outcome: &Outcome,
        seconds: f64,
        index: usize,
    ) -> PyResult_ {
        PyResult_ {
            data: Arc::new(Self::data_of(
                label,
                case,
                mesh,
                outcome,
                seconds,
                Some(index),
            )),
            outcome: Mutex::new(None),
            cache: Cache::default(),
        }
    }

    /// What a result holds.
    fn data_of(
        label: String,
        case: Case,
        mesh: PyMesh,
        outcome: &Outcome,
        seconds: f64,
        step: Option<usize>,
    ) -> ResultData {
        let (fields, totals) = outcome.fields();
        let fields = fields.into_owned();
        let quality = &outcome.discretization.quality;
        let mut summary = Summary::new(&label, outcome, quality, &totals);
        summary.run_id = new_run_id();
        summary.input_hash = input_hash(&case);
        summary.time_total_s = seconds;
        ResultData {
            label,
            case,
            mesh,
            fields,
            summary,
            // The result holds the fields in the user's numbering: the report's own copy
            // (the solver's numbering) would only double them.
            report: Report {
                derived: None,
                ..outcome.report.clone()
            },
            warnings: outcome.discretization.warnings.clone(),
            seconds,
            step,
            estimator: None,
        }
    }

    /// What the result holds.
    pub fn data(&self) -> &ResultData {
        &self.data
    }

    /// The outcome, rebuilt (assembled again on the stored mesh) when the result was
    /// unpickled.
    pub fn outcome(&self) -> memcontact::Result<Arc<Outcome>> {
        let mut slot = self.outcome.lock().unwrap_or_else(|p| p.into_inner());
        if let Some(o) = slot.as_ref() {
            return Ok(o.clone());
        }
        let d = &self.data;
        let hierarchy = (*d.mesh.hierarchy).clone();
        let discretization = match d.step {
            Some(index) => step_discretization(&d.case, index, hierarchy, &mut Silent)?,
            None => Discretization::assemble(&d.case.problem, hierarchy, &mut Silent)?,
        };
        let o = Arc::new(Outcome {
            discretization,
            report: d.report.clone(),
        });
        *slot = Some(o.clone());
        Ok(o)
    }

    fn f64_array<'py>(py: Python<'py>, v: &[f64]) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, v)
    }

    /// The read-only view of a vector of this result's data, made once: `pick` chooses
    /// the vector (None: the result has no such field).
    fn view<'py, T: numpy::Element>(
        &self,
        py: Python<'py>,
        slot: Slot,
        pick: impl Fn(&ResultData) -> Option<&[T]>,
    ) -> PyResult<Option<Bound<'py, PyAny>>> {
        if pick(&self.data).is_none() {
            return Ok(None);
        }
        self.cache
            .get(py, slot as usize, || {
                let data = pick(&self.data).expect("checked above");
                let owner = views::owner(py, self.data.clone())?;
                // SAFETY: the vector belongs to the immutable `ResultData` behind the `Arc`
                // the owner holds: it neither moves nor changes while the owner lives.
                unsafe { views::view1(data, &owner) }
            })
            .map(Some)
    }

    /// [`PyResult_::view`] of a field every result has.
    fn field<'py, T: numpy::Element>(
        &self,
        py: Python<'py>,
        slot: Slot,
        pick: impl Fn(&ResultData) -> &[T],
    ) -> PyResult<Bound<'py, PyAny>> {
        Ok(self
            .view(py, slot, |d| Some(pick(d)))?
            .expect("every result has the field"))
    }

    /// The deflection picture (`deflection.png` of the result set) as PNG bytes, drawn in
    /// memory.
    fn deflection_png(&self) -> memcontact::Result<Vec<u8>> {
        let d = &self.data;
        let options = plot_options(&d.case, &d.label);
        memcontact::write::render_png(
            d.mesh.hierarchy.finest(),
            &d.fields,
            &options,
            PlotKind::Deflection,
        )
    }
}

/// The assembled system of an outcome as Python values: arrays over the unknowns and the
/// compressed rows of its matrices (`memcontact._notebook.matrices` makes them
/// scipy.sparse matrices).
fn system_parts<'py>(py: Python<'py>, s: &System) -> PyResult<Bound<'py, PyDict>> {
    let rows = |m: &SparseRows| -> PyResult<Bound<'py, PyTuple>> {
        let ptr: Vec<i64> = m.row_ptr.iter().map(|&x| x as i64).collect();
        let col: Vec<i64> = m.col.iter().map(|&x| i64::from(x)).collect();
        PyTuple::new(
            py,
            [
                PyArray1::from_vec(py, ptr).into_any(),
                PyArray1::from_vec(py, col).into_any(),
                PyArray1::from_slice(py, &m.val).into_any(),
            ],
        )
    };
    let body = |b: &SystemBody| -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        match &b.l {
            Some(l) => d.set_item("L", rows(l)?)?,
            None => d.set_item("L", py.None())?,
        }
        d.set_item("lumped", b.lumped)?;
        d.set_item("phi", PyArray1::from_slice(py, &b.phi))?;
        d.set_item("can_touch", PyArray1::from_slice(py, &b.can_touch))?;
        d.set_item("rigid", PyArray1::from_slice(py, &b.rigid))?;
        Ok(d)
    };
    let d = PyDict::new(py);
    let unknowns: Vec<i64> = s.unknowns.iter().map(|&v| i64::from(v)).collect();
    d.set_item("unknowns", PyArray1::from_vec(py, unknowns))?;
    d.set_item("S", rows(&s.s)?)?;
    d.set_item("D", PyArray1::from_slice(py, &s.d))?;
    d.set_item("obstacle", body(&s.obstacle)?)?;
    match &s.lower {
        Some(b) => d.set_item("lower", body(b)?)?,
        None => d.set_item("lower", py.None())?,
    }
    Ok(d)
}

/// The serialisable form of a [`Report`] (for pickling).
#[derive(Serialize, Deserialize)]
struct ReportState {
    status: Status,
    accepted: bool,
    requested: Method,
    method: Method,
    #[serde(default)]
    coarsening: Option<memcontact::solve::HierarchyKind>,
    choice: Choice,
    fallback: Option<Fallback>,
    message: Option<String>,
    iterations: usize,
    energy: f64,
    certificate: Certificate,
    tolerance: f64,
    history: Vec<IterationRecord>,
    phases: Vec<(String, f64)>,
    solver_phases: Vec<(String, f64)>,
}

/// The small part of a pickled result, as TOML.
#[derive(Serialize, Deserialize)]
struct Meta {
    label: String,
    case: String,
    summary: Summary,
    report: ReportState,
    warnings: Vec<String>,
    seconds: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    step: Option<usize>,
}

fn phases_out(p: &[Phase]) -> Vec<(String, f64)> {
    p.iter().map(|p| (p.name.clone(), p.seconds)).collect()
}

fn phases_in(p: Vec<(String, f64)>) -> Vec<Phase> {
    p.into_iter()
        .map(|(name, seconds)| Phase { name, seconds })
        .collect()
}

const FIELD_NAMES: [&str; 5] = ["u", "phi", "penetration", "pressure", "contact_force"];

/// The body below's float fields in a pickled result.
const LOWER_NAMES: [&str; 4] = [
    "phi_low",
    "penetration_low",
    "pressure_low",
    "contact_force_low",
];

#[pymethods]
impl PyResult_ {
    /// The deflection u at every vertex (u = 0 on the boundary), in the mesh's vertex order.
    #[getter]
    fn u<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.field(py, Slot::U, |d| &d.fields.u)
    }

    /// The sampled obstacle surface φₙ at every vertex.
    #[getter]
    fn phi<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.field(py, Slot::Phi, |d| &d.fields.phi)
    }

    /// The penetration (u − φ)⁺ at every vertex (0 where the obstacle cannot touch).
    #[getter]
    fn penetration<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.field(py, Slot::Penetration, |d| &d.fields.penetration)
    }

    /// The contact pressure h (u − φ)⁺ (rigid obstacle: contact force per nodal area).
    #[getter]
    fn pressure<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.field(py, Slot::Pressure, |d| &d.fields.pressure)
    }

    /// The nodal contact force X₁ = D − SU on M (0 elsewhere).
    #[getter]
    fn contact_force<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.field(py, Slot::ContactForce, |d| &d.fields.contact_force)
    }

    /// The vertex state: −1 clear, 0 touching (U = φ), 1 penetrating (int8).
    #[getter]
    fn state<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.field(py, Slot::State, |d| &d.fields.state)
    }

    /// The body below's sampled surface φ_low at every vertex (`None` without one).
    #[getter]
    fn phi_low<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        self.view(py, Slot::PhiLow, |d| {
            d.fields.lower.as_ref().map(|l| l.phi.as_slice())
        })
    }

    /// The penetration into the body below (φ_low − u)⁺ (`None` without one).
    #[getter]
    fn penetration_low<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        self.view(py, Slot::PenetrationLow, |d| {
            d.fields.lower.as_ref().map(|l| l.penetration.as_slice())
        })
    }

    /// The body below's contact pressure (pushing up; `None` without one).
    #[getter]
    fn pressure_low<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        self.view(py, Slot::PressureLow, |d| {
            d.fields.lower.as_ref().map(|l| l.pressure.as_slice())
        })
    }

    /// The body below's nodal contact force (pushing up; `None` without one).
    #[getter]
    fn contact_force_low<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        self.view(py, Slot::ContactForceLow, |d| {
            d.fields.lower.as_ref().map(|l| l.contact_force.as_slice())
        })
    }

    /// The state toward the body below: −1 clear, 0 touching (U = φ_low), 1 sunk into it
    /// (int8; `None` without a body below).
    #[getter]
    fn state_low<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        self.view(py, Slot::StateLow, |d| {
            d.fields.lower.as_ref().map(|l| l.state.as_slice())
        })
    }

    /// For the last step of an adaptive loop: the error estimator η_T, one value per
    /// triangle of the mesh (energy-norm units); None for other results.
    #[getter]
    fn estimator<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        self.view(py, Slot::Estimator, |d| d.estimator.as_deref())
    }

    /// How the solve ended: "converged", "rounding_floor", "iteration_limit", "stalled"
    /// or "numerical_failure".
    #[getter]
    fn status(&self) -> &'static str {
        self.data.report.status.name()
    }

    /// Whether the certificate reached the tolerance.
    #[getter]
    fn converged(&self) -> bool {
        self.data.report.status.is_converged()
    }

    /// Whether the settings accept the outcome: converged, or at the rounding floor of
    /// double precision when the settings allow it (what `solve` checks).
    #[getter]
    fn accepted(&self) -> bool {
        self.data.report.accepted
    }

    /// What went wrong, for a solve that was not accepted (None otherwise).
    #[getter]
    fn message(&self) -> Option<String> {
        self.data.report.error().map(|e| e.to_string())
    }

    /// The method that produced the answer.
    #[getter]
    fn method(&self) -> &'static str {
        self.data.report.method.name()
    }

    /// Iterations of that method.
    #[getter]
    fn iterations(&self) -> usize {
        self.data.report.iterations
    }

    /// J(U), the energy of Problem 2b.
    #[getter]
    fn energy(&self) -> f64 {
        self.data.report.energy
    }

    /// The scaled KKT residual (the larger of the residuals of 2e and 2f).
    #[getter]
    fn kkt_residual(&self) -> f64 {
        self.data.report.certificate.kkt()
    }

    /// The report: status, requested and used method and why, iterations, energy,
    /// certificate, tolerance, history, phase times (a new dict).
    #[getter]
    fn report<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_py(py, &self.data.report)
    }

    /// The scalars of `summary.json` (the same keys; `files` is filled in by `write`).
    #[getter]
    fn summary<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_py(py, &self.data.summary)
    }

    /// The solved mesh.
    #[getter]
    fn mesh<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.cache.get(py, Slot::Mesh as usize, || {
            Ok(Bound::new(py, self.data.mesh.clone())?.into_any())
        })
    }

    /// The case solved.
    #[getter]
    fn case(&self) -> PyCase {
        PyCase {
            case: self.data.case.clone(),
            label: self.data.label.clone(),
        }
    }

    /// Warnings from reading the mesh.
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.data.warnings.clone()
    }

    /// For a step of a sweep: its index among the case's steps (None for a single solve).
    #[getter]
    fn step(&self) -> Option<usize> {
        self.data.step
    }

    /// Writes the result set the command-line tool writes (`solution.vtu`, `nodes.csv`,
    /// the pictures of the case's `[output] plots` unless `pictures` is false, and
    /// `summary.json`) into `directory`, atomically; `vtu` ("binary", "ascii" or
    /// "compressed") defaults to the case's `[output] vtu`. A directory holding other files
    /// is refused unless `force`. Returns the summary written.
    #[pyo3(signature = (directory, force=false, vtu=None, pictures=true))]
    fn write<'py>(
        &self,
        py: Python<'py>,
        directory: PathBuf,
        force: bool,
        vtu: Option<&str>,
        pictures: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        let vtu = vtu_format(vtu, &self.data.case)?;
        let summary = crate::convert::detached(py, || {
            let outcome = self.outcome()?;
            let mut plots = plot_options(&self.data.case, &self.data.label);
            if !pictures {
                plots.plots.clear();
            }
            let now = Instant::now();
            let options = WriteOptions {
                label: self.data.label.clone(),
                vtu,
                force,
                started: now
                    .checked_sub(Duration::from_secs_f64(self.data.seconds))
                    .unwrap_or(now),
                plot_options: None,
                run_id: None,
                cell_data: Vec::new(),
                adapt: None,
                unconverged: false,
            };
            write_result(&directory, &outcome, &self.data.case, &options, &plots)
        })
        .map_err(py_err)?;
        to_py(py, &summary)
    }

    /// The assembled discrete problem over the unknowns (docs/theory.md#discrete-model,
    /// docs/theory.md#extensions), for scipy.
    ///
    /// Unknown `k` is vertex `unknowns[k]` (increasing): `U = result.u[m["unknowns"]]`.
    /// U minimises `½ VᵀSV − VᵀD + ½ pᵀLp` (`p = (V − φ)⁺`; with a body below
    /// `+ ½ qᵀ L_low q`, `q = (φ_low − V)⁺`).
    ///
    /// Returns
    /// -------
    /// dict
    ///     `S` and `L` (scipy.sparse.csr_array; L the consistent foundation matrix or the
    ///     lumped diagonal; None for a rigid obstacle, whose condition is U ≤ φ), `D`
    ///     (the load minus the lifting of the boundary heights), `phi`, `unknowns`,
    ///     `can_touch` (M), `rigid`, `foundation`; with a body below `L_low`, `phi_low`,
    ///     `can_touch_low`, `rigid_low`, `foundation_low`.
    ///
    /// Raises
    /// ------
    /// ImportError
    ///     scipy is not installed.
    fn matrices<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        let py = slf.py();
        let this = slf.get();
        let system = crate::convert::detached(py, || this.outcome()?.system()).map_err(py_err)?;
        let parts = system_parts(py, &system)?;
        crate::convert::call_helper(py, "matrices", (parts,), None)
    }

    /// Draws a field on the mesh with matplotlib, each body's contact outlined (the
    /// obstacle's solid black, the body below's dashed red), with a colour bar.
    ///
    /// Parameters
    /// ----------
    /// field : str or array_like
    ///     `u` (default), `phi`, `penetration`, `pressure`, `contact_force`, `state`,
    ///     `gap` (φ − u), with a body below the `_low` fields and `gap_low` (u − φ_low),
    ///     the cell fields `region` and `estimator`; or one value per vertex or triangle.
    /// ax : matplotlib.axes.Axes, optional
    ///     Where to draw (default: a new figure).
    /// **kwargs
    ///     `kind` ("tripcolor" or "tricontourf"), `levels`, `contact`, `colorbar`,
    ///     `title`; the rest goes to matplotlib (`cmap`, `vmin`, ...).
    ///
    /// Returns
    /// -------
    /// matplotlib.axes.Axes
    ///
    /// Raises
    /// ------
    /// ValueError, TypeError
    ///     An unknown field or an array of the wrong size or type.
    /// ImportError
    ///     matplotlib is not installed.
    #[pyo3(
        signature = (field=None, ax=None, **kwargs),
        text_signature = "($self, field='u', ax=None, **kwargs)"
    )]
    fn plot<'py>(
        slf: &Bound<'py, Self>,
        field: Option<&Bound<'py, PyAny>>,
        ax: Option<&Bound<'py, PyAny>>,
        kwargs: Option<&Bound<'py, PyDict>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        crate::convert::call_helper(slf.py(), "result_plot", (slf, field, ax), kwargs)
    }

    /// The result as a `meshio.Mesh`: points (z = 0), triangles, every point field of
    /// `nodes.csv` and the cell fields `region` (and `estimator`), as copies.
    ///
    /// Returns
    /// -------
    /// meshio.Mesh
    ///
    /// Raises
    /// ------
    /// ImportError
    ///     meshio is not installed.
    fn to_meshio<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        crate::convert::call_helper(slf.py(), "result_to_meshio", (slf,), None)
    }

    /// The result as a `pyvista.UnstructuredGrid` with every point and cell field.
    ///
    /// Returns
    /// -------
    /// pyvista.UnstructuredGrid
    ///
    /// Raises
    /// ------
    /// ImportError
    ///     pyvista is not installed.
    fn to_pyvista<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        crate::convert::call_helper(slf.py(), "result_to_pyvista", (slf,), None)
    }

    /// The notebook's summary table (HTML).
    fn _repr_html_<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        crate::convert::call_helper(slf.py(), "result_html", (slf,), None)
    }

    /// The deflection picture of the result set (`deflection.png`), drawn in memory once,
    /// as PNG bytes (IPython asks for it at every display of the result).
    fn _repr_png_<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.cache.get(py, Slot::Png as usize, || {
            let png = crate::convert::detached(py, || self.deflection_png()).map_err(py_err)?;
            Ok(PyBytes::new(py, &png).into_any())
        })
    }

    fn __repr__(&self) -> String {
        let r = &self.data.report;
        format!(
            "Result({}, {} vertices, method {}, {} iterations, KKT {:.2e})",
            r.status.name(),
            self.data.fields.u.len(),
            r.method.name(),
            r.iterations,
            r.certificate.kkt()
        )
    }

    /// Pickling: the fields, the iterate, the mesh levels and (as TOML) the case, summary
    /// and report.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        let d = &self.data;
        let r = &d.report;
        let meta = Meta {
            label: d.label.clone(),
            case: d.case.to_toml_string().map_err(py_err)?,
            summary: d.summary.clone(),
            report: ReportState {
                status: r.status,
                accepted: r.accepted,
                requested: r.requested,
                method: r.method,
                coarsening: r.coarsening,
                choice: r.choice,
                fallback: r.fallback.clone(),
                message: r.message.clone(),
                iterations: r.iterations,
                energy: r.energy,
                certificate: r.certificate,
                tolerance: r.tolerance,
                history: r.history.clone(),
                phases: phases_out(&r.phases),
                solver_phases: phases_out(&r.solver_phases),
            },
            warnings: d.warnings.clone(),
            seconds: d.seconds,
            step: d.step,
        };
        let state = PyDict::new(py);
        // TOML, not JSON: it keeps NaN (residuals that were not computed).
        state.set_item(
            "meta",
            toml::to_string(&meta)
                .map_err(|e| PyValueError::new_err(format!("cannot pickle: {e}")))?,
        )?;
        let f = &d.fields;
        for (name, v) in
            FIELD_NAMES
                .iter()
                .zip([&f.u, &f.phi, &f.penetration, &f.pressure, &f.contact_force])
        {
            state.set_item(*name, Self::f64_array(py, v))?;
        }
        state.set_item("state", PyArray1::from_slice(py, &f.state))?;
        state.set_item("covered", PyArray1::from_slice(py, &f.covered))?;
        if let Some(l) = &f.lower {
            for (name, v) in
                LOWER_NAMES
                    .iter()
                    .zip([&l.phi, &l.penetration, &l.pressure, &l.contact_force])
            {
                state.set_item(*name, Self::f64_array(py, v))?;
            }
            state.set_item("state_low", PyArray1::from_slice(py, &l.state))?;
            state.set_item("covered_low", PyArray1::from_slice(py, &l.covered))?;
        }
        state.set_item("u_dofs", Self::f64_array(py, &r.u))?;
        if let Some(m) = &r.multipliers {
            state.set_item("x1", Self::f64_array(py, &m.x1))?;
            state.set_item("x2", Self::f64_array(py, &m.x2))?;
            if !m.x1_low.is_empty() {
                state.set_item("x1_low", Self::f64_array(py, &m.x1_low))?;
                state.set_item("x2_low", Self::f64_array(py, &m.x2_low))?;
            }
        }
        if let Some(eta) = &d.estimator {
            state.set_item("estimator", Self::f64_array(py, eta))?;
        }
        state.set_item("mesh", mesh_state(py, &d.mesh.hierarchy)?)?;
        let rebuild = py
            .import("memcontact._memcontact")?
            .getattr("_result_from_state")?;
        PyTuple::new(py, [rebuild, PyTuple::new(py, [state])?.into_any()])
    }
}

fn vec_bool(a: &Bound<'_, PyAny>) -> PyResult<Vec<bool>> {
    let a: PyReadonlyArray1<'_, bool> = a.extract()?;
    Ok(a.as_array().to_vec())
}

/// The encoding of `solution.vtu`: `vtu` ("binary", "ascii" or "compressed"), or the case's.
pub fn vtu_format(vtu: Option<&str>, case: &Case) -> PyResult<VtuFormat> {
    match vtu {
        None => Ok(case.output.vtu),
        Some("binary") => Ok(VtuFormat::Binary),
        Some("ascii") => Ok(VtuFormat::Ascii),
        Some("compressed") => Ok(VtuFormat::Compressed),
        Some(other) => Err(PyValueError::new_err(format!(
            "vtu: \"{other}\" is unknown (choose binary, ascii or compressed)"
        ))),
    }
}

/// Rebuilds a pickled result.
#[pyfunction]
pub fn _result_from_state(state: &Bound<'_, PyDict>) -> PyResult<PyResult_> {
    let get = |k: &str| -> PyResult<Bound<'_, PyAny>> {
        state
            .get_item(k)?
            .ok_or_else(|| PyValueError::new_err(format!("result state without '{k}'")))
    };
    let vec = |k: &str| -> PyResult<Vec<f64>> {
        let a: PyReadonlyArray1<'_, f64> = get(k)?.extract()?;
        Ok(a.as_array().to_vec())
    };
    let meta: Meta = toml::from_str(&get("meta")?.extract::<String>()?)
        .map_err(|e| PyValueError::new_err(format!("cannot unpickle a result: {e}")))?;
    let case = Case::from_toml_str(&meta.case, None).map_err(py_err)?;
    let state_arr: PyReadonlyArray1<'_, i8> = get("state")?.extract()?;
    let fields = NodalFields {
        covered: vec_bool(&get("covered")?)?,
        u: vec("u")?,
        phi: vec("phi")?,
        penetration: vec("penetration")?,
        pressure: vec("pressure")?,
        contact_force: vec("contact_force")?,
        state: state_arr.as_array().to_vec(),
        lower: match state.get_item("phi_low")? {
            Some(_) => {
                let state_low: PyReadonlyArray1<'_, i8> = get("state_low")?.extract()?;
                Some(LowerFields {
                    phi: vec("phi_low")?,
                    penetration: vec("penetration_low")?,
                    pressure: vec("pressure_low")?,
                    contact_force: vec("contact_force_low")?,
                    state: state_low.as_array().to_vec(),
                    covered: vec_bool(&get("covered_low")?)?,
                })
            }
            None => None,
        },
    };
    let multipliers = match state.get_item("x1")? {
        Some(_) => Some(Multipliers {
            x1: vec("x1")?,
            x2: vec("x2")?,
            x1_low: match state.get_item("x1_low")? {
                Some(_) => vec("x1_low")?,
                None => Vec::new(),
            },
            x2_low: match state.get_item("x2_low")? {
                Some(_) => vec("x2_low")?,
                None => Vec::new(),
            },
        }),
        None => None,
    };
    let s = meta.report;
    let report = Report {
        status: s.status,
        accepted: s.accepted,
        requested: s.requested,
        method: s.method,
        coarsening: s.coarsening,
        choice: s.choice,
        fallback: s.fallback,
        message: s.message,
        iterations: s.iterations,
        energy: s.energy,
        certificate: s.certificate,
        tolerance: s.tolerance,
        history: s.history,
        phases: phases_in(s.phases),
        solver_phases: phases_in(s.solver_phases),
        u: vec("u_dofs")?,
        multipliers,
        derived: None,
    };
    let mesh = PyMesh::new_from(hierarchy_from_state(&get("mesh")?)?);
    // A mesh given as data travels as the result's mesh; the case gets it back.
    let mut case = case;
    if let memcontact::problem::MeshSource::Given(g) = &mut case.problem.mesh.source {
        g.hierarchy = Some(mesh.hierarchy.clone());
    }
    Ok(PyResult_ {
        data: Arc::new(ResultData {
            label: meta.label,
            case,
            mesh,
            fields,
            summary: meta.summary,
            report,
            warnings: meta.warnings,
            seconds: meta.seconds,
            step: meta.step,
            estimator: match state.get_item("estimator")? {
                Some(_) => Some(vec("estimator")?),
                None => None,
            },
        }),
        outcome: Mutex::new(None),
        cache: Cache::default(),
    })
}
