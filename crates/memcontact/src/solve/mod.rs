//! Solvers of the discrete problem, each a real implementation of one of the paper's
//! equivalent formulations, all on the same [`Model`]:
//!
//! | method | formulation |
//! | --- | --- |
//! | [`Method::Linear`] | h ≡ 0: one sparse Cholesky solve of `S U = D` |
//! | [`Method::ActiveSet`] | Problem 2f: semismooth (truncated) Newton with three vertex states |
//! | [`Method::Qp`] | Problem 2c handed to the Clarabel interior-point solver (multipliers of 2d/2e) |
//! | [`Method::Coordinate`] | Problem 2b: exact coordinatewise minimisation of J (docs/theory.md#coordinatewise-optimality) |
//! | [`Method::Multigrid`] | Problem 2b: truncated nonsmooth Newton multigrid |
//!
//! Every solve ends with the certificates of 2e and 2f; not reaching the tolerance is an
//! error, never a silently returned iterate.

pub(crate) mod active_set;
pub(crate) mod coordinate;
pub(crate) mod line_search;
pub(crate) mod linear;
pub(crate) mod multigrid;
pub(crate) mod newton;
pub(crate) mod qp;
pub(crate) mod relax;

pub use crate::certificate::Certificate;
use crate::error::{Error, Result};
use crate::mesh::refine::Hierarchy;
use crate::model::Model;
pub use multigrid::Kind as HierarchyKind;
use std::time::Instant;

/// The solution methods.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// Pick the best method for the case.
    Auto,
    /// One linear solve (h ≡ 0 only).
    Linear,
    /// Semismooth Newton / primal-dual active set on Problem 2f.
    #[serde(alias = "active_set")]
    ActiveSet,
    /// Problem 2c by an interior-point QP solver.
    Qp,
    /// Exact coordinate minimisation of J (Problem 2b).
    Coordinate,
    /// Truncated nonsmooth Newton multigrid (needs a mesh hierarchy).
    Multigrid,
}

impl Method {
    /// All names accepted in case files.
    pub const NAMES: &'static str = "auto, linear, active-set, qp, coordinate, multigrid";

    /// The name used in case files and outputs.
    pub fn name(self) -> &'static str {
        match self {
            Method::Auto => "auto",
            Method::Linear => "linear",
            Method::ActiveSet => "active-set",
            Method::Qp => "qp",
            Method::Coordinate => "coordinate",
            Method::Multigrid => "multigrid",
        }
    }
}

impl std::str::FromStr for Method {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        Ok(match s {
            "auto" => Method::Auto,
            "linear" => Method::Linear,
            "active-set" | "active_set" => Method::ActiveSet,
            "qp" => Method::Qp,
            "coordinate" => Method::Coordinate,
            "multigrid" => Method::Multigrid,
            _ => {
                return Err(Error::Data(format!(
                    "unknown solver method \"{s}\" (choose one of {})",
                    Method::NAMES
                )))
            }
        })
    }
}

/// Solver settings (`[solver]` in a case file), with serde defaults; [`Settings::validate`]
/// refuses values that cannot certify an answer.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Settings {
    /// The method.
    pub method: Method,
    /// Stop when the scaled KKT residual (max of 2e and 2f) is at most this.
    pub tolerance: f64,
    /// Iteration limit (`None`: the method's default).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_iterations: Option<usize>,
    /// Accept a solve whose residual stops at the rounding floor of double precision above
    /// the tolerance (reported as [`Status::RoundingFloor`]); `false` makes it a failure.
    pub accept_rounding_floor: bool,
    /// The coarse levels of the multigrid method.
    pub hierarchy: HierarchyChoice,
    /// Stops the solve when cancelled (checked every iteration and inside the multigrid
    /// iteration; not part of a case file).
    #[serde(skip)]
    pub cancel: crate::parallel::Cancel,
}

/// Which coarse levels the multigrid method uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum HierarchyChoice {
    /// The mesh's refinement levels when it has them, an algebraic hierarchy otherwise.
    #[default]
    Auto,
    /// The mesh's refinement levels (an error without them).
    Geometric,
    /// An aggregation hierarchy built from the matrices, even when the mesh has levels.
    Algebraic,
}

/// Tolerances at or above this certify nothing: a residual of 1 % of the forces.
pub const LOOSEST_TOLERANCE: f64 = 1e-2;

impl Settings {
    /// Checks the settings: `0 < tolerance <` [`LOOSEST_TOLERANCE`], `max_iterations ≥ 1`.
    pub fn validate(&self) -> std::result::Result<(), crate::error::Invalid> {
        use crate::error::Invalid;
        let tol = self.tolerance;
        if !(tol.is_finite() && tol > 0.0) {
            return Err(Invalid::new(
                "solver.tolerance",
                format!("must be a finite number > 0, got {tol}"),
            ));
        }
        if tol >= LOOSEST_TOLERANCE {
            return Err(Invalid::new(
                "solver.tolerance",
                format!(
                    "{tol} cannot certify an answer: the scaled KKT residual measures the \
                     unbalanced force relative to the forces present, so a tolerance must be \
                     below {LOOSEST_TOLERANCE:e} (1e-10 by default)"
                ),
            ));
        }
        if self.max_iterations == Some(0) {
            return Err(Invalid::new("solver.max_iterations", "must be at least 1"));
        }
        Ok(())
    }
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            method: Method::Auto,
            tolerance: 1e-10,
            max_iterations: None,
            accept_rounding_floor: true,
            hierarchy: HierarchyChoice::Auto,
            cancel: crate::parallel::Cancel::default(),
        }
    }
}

/// One line of a solver's history.
#[derive(Debug, Clone, Copy, serde::Serialize, serde::Deserialize)]
pub struct IterationRecord {
    /// Iteration number (1-based).
    pub iteration: usize,
    /// J after the iteration.
    pub energy: f64,
    /// The scaled KKT residual after the iteration (NaN when not computed).
    pub residual: f64,
    /// The scaled residual of 2e after the iteration.
    #[serde(default)]
    pub residual_2e: f64,
    /// The scaled residual of 2f after the iteration.
    #[serde(default)]
    pub residual_2f: f64,
    /// The vertex states after the iteration.
    #[serde(default, flatten)]
    pub states: crate::certificate::StateCounts,
}

impl IterationRecord {
    /// The record of iteration `iteration` from the evaluation of its iterate.
    pub fn new(iteration: usize, ev: &crate::certificate::Evaluation) -> IterationRecord {
        IterationRecord {
            iteration,
            energy: ev.energy,
            residual: ev.certificate.kkt(),
            residual_2e: ev.certificate.residual_2e,
            residual_2f: ev.certificate.residual_2f,
            states: ev.states,
        }
    }
}

/// Receives progress from a run (the CLI draws it; the library never prints).
pub trait Observer {
    /// Called after every iteration.
    fn iteration(&mut self, _record: &IterationRecord) {}
    /// A phase of the run (`mesh`, `assembly`, `solve`, ...) starts.
    fn phase_started(&mut self, _name: &str) {}
    /// A phase of the run ends after `seconds`.
    fn phase_finished(&mut self, _name: &str, _seconds: f64) {}
    /// Step `index` (0-based) of `total` of a sweep starts.
    fn step_started(&mut self, _index: usize, _total: usize, _name: &str) {}
    /// Whether the run should stop (asked between the phases of a run).
    fn cancelled(&self) -> bool {
        false
    }
}

/// An observer that also answers [`Observer::cancelled`] from a token (the runs wrap the
/// caller's observer with their settings' token).
pub struct Cancellable<'a> {
    /// The caller's observer.
    pub inner: &'a mut dyn Observer,
    /// The token.
    pub cancel: &'a crate::parallel::Cancel,
}

impl<'a> Cancellable<'a> {
    /// `observer`, stopped by `cancel` too: how every run wraps its caller's observer with
    /// its settings' token.
    pub fn new(observer: &'a mut dyn Observer, cancel: &'a crate::parallel::Cancel) -> Self {
        Cancellable {
            inner: observer,
            cancel,
        }
    }
}

impl Observer for Cancellable<'_> {
    fn iteration(&mut self, record: &IterationRecord) {
        self.inner.iteration(record)
    }
    fn phase_started(&mut self, name: &str) {
        self.inner.phase_started(name)
    }
    fn phase_finished(&mut self, name: &str, seconds: f64) {
        self.inner.phase_finished(name, seconds)
    }
    fn step_started(&mut self, index: usize, total: usize, name: &str) {
        self.inner.step_started(index, total, name)
    }
    fn cancelled(&self) -> bool {
        self.cancel.is_cancelled() || self.inner.cancelled()
    }
}

/// An observer that ignores everything.
pub struct Silent;
impl Observer for Silent {}

/// Multipliers of the Kuhn-Tucker system 2e, over the vertices of M (zero elsewhere).
#[derive(Debug, Clone, Default)]
pub struct Multipliers {
    /// X₁: the contact forces the obstacle exerts.
    pub x1: Vec<f64>,
    /// X₂: the multipliers of `U₂ ≥ 0`.
    pub x2: Vec<f64>,
    /// The body below's contact forces (pushing up; empty without a body below).
    pub x1_low: Vec<f64>,
    /// The multipliers of `U₃ ≥ 0` (the body below's penetration variables).
    pub x2_low: Vec<f64>,
}

/// A solver's answer.
#[derive(Debug, Clone)]
pub struct Solution {
    /// U over the unknowns.
    pub u: Vec<f64>,
    /// The method that produced it.
    pub method: Method,
    /// Iterations (Newton steps, sweeps, interior-point iterations, ...).
    pub iterations: usize,
    /// J(U).
    pub energy: f64,
    /// The certificates at U.
    pub certificate: Certificate,
    /// The solver's own multipliers, when it computes them (the QP does).
    pub multipliers: Option<Multipliers>,
    /// Per-iteration history.
    pub history: Vec<IterationRecord>,
    /// Wall-clock seconds per phase (setup, factorisation, iterations, ...).
    pub phases: Vec<(String, f64)>,
    /// The kind of hierarchy, for the multigrid method.
    pub coarsening: Option<multigrid::Kind>,
}

/// Times phases of a solve.
#[derive(Debug, Default)]
pub struct PhaseTimer {
    phases: Vec<(String, f64)>,
}

impl PhaseTimer {
    /// Runs `f` and records its time under `name` (accumulating repeated names).
    pub fn time<T>(&mut self, name: &str, f: impl FnOnce() -> T) -> T {
        let t0 = Instant::now();
        let out = f();
        self.add(name, t0.elapsed().as_secs_f64());
        out
    }

    /// Adds `seconds` to phase `name`.
    pub fn add(&mut self, name: &str, seconds: f64) {
        match self.phases.iter_mut().find(|p| p.0 == name) {
            Some(p) => p.1 += seconds,
            None => self.phases.push((name.to_string(), seconds)),
        }
    }

    /// The recorded phases.
    pub fn into_phases(self) -> Vec<(String, f64)> {
        self.phases
    }
}

/// How a solve ended. A numerical outcome is never an `Err`: every status comes with the
/// best iterate and its certificate.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Status {
    /// The scaled KKT residual reached the tolerance.
    Converged,
    /// The residual stopped at the rounding floor of double precision, above the
    /// tolerance: the iterate is as accurate as the arithmetic allows for these data.
    RoundingFloor,
    /// The iteration limit was reached first.
    IterationLimit,
    /// The iterate stopped changing before the tolerance was reached.
    Stalled,
    /// A factorisation or the arithmetic failed (non-finite values, a singular matrix).
    NumericalFailure,
}

impl Status {
    /// The name used in outputs.
    pub fn name(self) -> &'static str {
        match self {
            Status::Converged => "converged",
            Status::RoundingFloor => "rounding_floor",
            Status::IterationLimit => "iteration_limit",
            Status::Stalled => "stalled",
            Status::NumericalFailure => "numerical_failure",
        }
    }

    /// `true` for [`Status::Converged`].
    pub fn is_converged(self) -> bool {
        self == Status::Converged
    }

    /// `true` when the settings accept the outcome: converged, or at the rounding floor
    /// with [`Settings::accept_rounding_floor`].
    pub fn is_accepted(self, settings: &Settings) -> bool {
        self == Status::Converged
            || (self == Status::RoundingFloor && settings.accept_rounding_floor)
    }
}

/// Why the method of a solve was used.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Choice {
    /// The settings named the method.
    Requested,
    /// `auto`: h ≡ 0 (no body can touch), the problem is one linear solve.
    LinearProblem,
    /// `auto`: the mesh has a refinement hierarchy, so geometric multigrid.
    GeometricHierarchy,
    /// `auto`: no refinement hierarchy, so multigrid on an algebraic hierarchy.
    AlgebraicHierarchy,
    /// `auto`: a small problem without a refinement hierarchy, so the active-set method
    /// with a direct solver.
    NoHierarchy,
}

impl Choice {
    /// A one-line reason.
    pub fn reason(self) -> &'static str {
        match self {
            Choice::Requested => "requested",
            Choice::LinearProblem => "no body can touch the membrane: one linear solve",
            Choice::GeometricHierarchy => "the mesh has a refinement hierarchy: multigrid",
            Choice::AlgebraicHierarchy => {
                "no refinement hierarchy: multigrid on an algebraic (aggregation) hierarchy"
            }
            Choice::NoHierarchy => {
                "a small problem without refinement hierarchy: active-set with a direct solver"
            }
        }
    }
}

/// A method `auto` tried first and gave up on.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Fallback {
    /// The method tried first.
    pub from: Method,
    /// How it ended.
    pub status: Status,
    /// Its scaled KKT residual at the end.
    pub residual: f64,
    /// What happened, when it failed.
    pub message: Option<String>,
}

/// What one solve produced: the iterate and how the solve ended.
#[derive(Debug, Clone)]
pub struct Attempt {
    /// The best iterate, its certificate and history.
    pub solution: Solution,
    /// How the solve ended.
    pub status: Status,
    /// The method the settings asked for (maybe `auto`).
    pub requested: Method,
    /// Why `solution.method` was used.
    pub choice: Choice,
    /// The method `auto` tried first, when it fell back.
    pub fallback: Option<Fallback>,
    /// What went wrong, for a numerical failure.
    pub message: Option<String>,
}

/// From this many unknowns on, `auto` solves a mesh without refinement hierarchy by
/// multigrid on an algebraic hierarchy rather than by the active-set method with its
/// sparse Cholesky factorisations. Measured on imported Gmsh site meshes (2 cores): 10⁴
/// unknowns 0.03 s against 0.06 s, 2.5·10⁴ 0.10 s against 0.19 s, 10⁵ 0.38 s against
/// 1.3 s; below, both take milliseconds and the direct method's answer is the sharper.
pub const ALGEBRAIC_FROM: usize = 10_000;

/// The one `auto` policy: linear when no body can touch (L = 0), multigrid on the mesh's
/// refinement hierarchy when it has one (of three levels or more, or of two for a large
/// mesh), multigrid on an algebraic hierarchy for a large mesh without one, the
/// active-set method otherwise; with the reason.
pub fn auto_choice(model: &Model, hierarchy: Option<&Hierarchy>) -> (Method, Choice) {
    let depth = hierarchy.map_or(0, Hierarchy::depth);
    if model.is_linear() {
        (Method::Linear, Choice::LinearProblem)
    } else if depth >= 3 || (depth == 2 && model.n() >= ALGEBRAIC_FROM) {
        // Multigrid runs on the mesh levels whenever there are two (see `run_method`).
        (Method::Multigrid, Choice::GeometricHierarchy)
    } else if model.n() >= ALGEBRAIC_FROM {
        (Method::Multigrid, Choice::AlgebraicHierarchy)
    } else {
        (Method::ActiveSet, Choice::NoHierarchy)
    }
}

/// The method `auto` picks (see [`auto_choice`]).
pub fn auto_method(model: &Model, hierarchy: Option<&Hierarchy>) -> Method {
    auto_choice(model, hierarchy).0
}

impl Method {
    /// The iteration limit when the settings give none.
    pub fn default_max_iterations(self) -> usize {
        match self {
            Method::Auto | Method::Linear => 1,
            Method::ActiveSet => active_set::MAX_ITERATIONS,
            Method::Qp => qp::MAX_ITERATIONS as usize,
            Method::Coordinate => coordinate::MAX_SWEEPS,
            Method::Multigrid => multigrid::tnnmg::MAX_ITERATIONS,
        }
    }
}

/// Runs one method; a solver's numerical failure becomes a status with the start iterate.
fn run_method(
    method: Method,
    model: &Model,
    hierarchy: Option<&Hierarchy>,
    built: Option<&multigrid::Levels>,
    settings: &Settings,
    start: Option<&[f64]>,
    observer: &mut dyn Observer,
) -> Result<(Solution, Status, Option<String>)> {
    let result = match method {
        Method::Linear => linear::solve(model, settings),
        Method::ActiveSet => active_set::solve(model, settings, start, observer),
        Method::Qp => qp::solve(model, settings),
        Method::Coordinate => coordinate::solve_from(model, settings, start, observer),
        Method::Multigrid => {
            let coarsening = match (settings.hierarchy, hierarchy) {
                (HierarchyChoice::Algebraic, _) | (HierarchyChoice::Auto, None) => match built {
                    // Algebraic levels built beforehand for this pattern (a fit's iterates).
                    Some(levels) if levels.kind == multigrid::Kind::Algebraic => {
                        multigrid::Coarsening::Built(levels)
                    }
                    _ => multigrid::Coarsening::Algebraic,
                },
                (_, Some(h)) => match built {
                    Some(levels) if levels.kind == multigrid::Kind::Geometric => {
                        multigrid::Coarsening::Built(levels)
                    }
                    _ => multigrid::Coarsening::Geometric(h),
                },
                (HierarchyChoice::Geometric, None) => {
                    return Err(Error::Solver {
                        solver: "multigrid".into(),
                        message: "the mesh has no refinement hierarchy: set mesh.refine > 0, \
                                  use the rectangle generator with nx, ny divisible by a \
                                  power of two, or choose hierarchy = \"algebraic\""
                            .into(),
                    })
                }
            };
            multigrid::solve(model, coarsening, settings, start, observer)
        }
        Method::Auto => unreachable!("resolved by the caller"),
    };
    match result {
        Ok(solution) => {
            let kkt = solution.certificate.kkt();
            let limit = settings
                .max_iterations
                .unwrap_or(method.default_max_iterations());
            let floor = solution.certificate.rounding_floor;
            let (status, message) = if kkt <= settings.tolerance {
                (Status::Converged, None)
            } else if !kkt.is_finite() || !solution.energy.is_finite() {
                (Status::NumericalFailure, None)
            } else if floor > crate::certificate::FLOOR_LIMIT {
                (
                    Status::NumericalFailure,
                    Some(format!(
                        "the rounding floor of the residual is {floor:.1e}: the data's scales \
                         are beyond what double precision resolves (typically a stiffness h \
                         so large that the foundation force h(u − φ) comes from a penetration \
                         below the rounding of φ: use stiffness = \"rigid\", or rescale)"
                    )),
                )
            } else if solution.certificate.near_floor() {
                (Status::RoundingFloor, None)
            } else if solution.iterations >= limit {
                (Status::IterationLimit, None)
            } else {
                (Status::Stalled, None)
            };
            let message = match status {
                Status::Converged | Status::RoundingFloor => message,
                _ => message.or_else(|| conditioning(model)),
            };
            Ok((solution, status, message))
        }
        Err(Error::Solver { message, .. }) => {
            let message = match conditioning(model) {
                Some(c) => format!("{message}; {c}"),
                None => message,
            };
            let u = active_set::feasible_start(model);
            let certificate = model.certificate(&u);
            // The start may be the answer (f = 0 with the body clear, say), which the
            // method failed to confirm: the certificate, not the method, decides.
            let (status, message) = if certificate.kkt() <= settings.tolerance {
                (Status::Converged, None)
            } else {
                (Status::NumericalFailure, Some(message))
            };
            let solution = Solution {
                energy: model.energy(&u),
                u,
                method,
                iterations: 0,
                certificate,
                multipliers: None,
                history: Vec::new(),
                phases: Vec::new(),
                coarsening: None,
            };
            Ok((solution, status, message))
        }
        Err(e) => Err(e),
    }
}

/// Above this ratio of foundation to membrane stiffness (diagonals of L and S), solves in
/// double precision lose the balance between the two.
const STIFFNESS_RATIO_LIMIT: f64 = 1e6;

/// A note on the model's conditioning when the foundation is so much stiffer than the
/// membrane that a failed solve is explained by it.
fn conditioning(model: &Model) -> Option<String> {
    let s_min = (0..model.n())
        .map(|i| model.s.get(i, i))
        .fold(f64::INFINITY, f64::min);
    let l_max = (0..model.n())
        .map(|i| model.l.diag(i))
        .fold(0.0f64, f64::max);
    let ratio = l_max / s_min;
    (ratio > STIFFNESS_RATIO_LIMIT).then(|| {
        format!(
            "the foundation is {ratio:.1e} times stiffer than the membrane (diagonals of L and \
             S), beyond what double precision resolves well: use stiffness = \"rigid\" for \
             so stiff a body, or rescale the problem"
        )
    })
}

/// Solves the model with the settings' method (resolving `auto` by [`auto_choice`], with
/// its one fallback: when multigrid does not converge, the active-set method). `hierarchy`,
/// when given, must end with the mesh the model was assembled on. `Err` is for input the
/// method cannot take; every numerical outcome is an [`Attempt`] with a [`Status`].
pub fn attempt(
    model: &Model,
    hierarchy: Option<&Hierarchy>,
    settings: &Settings,
    observer: &mut dyn Observer,
) -> Result<Attempt> {
    attempt_from(model, hierarchy, settings, None, observer)
}

/// [`attempt`] from a given iterate (a warm start: the active-set, multigrid and
/// coordinate methods begin there; `linear` and `qp`, which need no start, ignore it). A
/// start of the wrong length is an error.
pub fn attempt_from(
    model: &Model,
    hierarchy: Option<&Hierarchy>,
    settings: &Settings,
    start: Option<&[f64]>,
    observer: &mut dyn Observer,
) -> Result<Attempt> {
    attempt_with_levels(model, hierarchy, None, settings, start, observer)
}

/// [`attempt_from`] with the hierarchy's geometric multigrid levels built beforehand
/// (`built`, for the model's unknowns and pattern): multigrid on the mesh's levels uses
/// them instead of building its own from `hierarchy`, which then only tells `auto` how
/// deep the hierarchy is.
pub fn attempt_with_levels(
    model: &Model,
    hierarchy: Option<&Hierarchy>,
    built: Option<&multigrid::Levels>,
    settings: &Settings,
    start: Option<&[f64]>,
    observer: &mut dyn Observer,
) -> Result<Attempt> {
    settings.validate().map_err(|e| e.into_error())?;
    if let Some(s) = start {
        if s.len() != model.n() || s.iter().any(|v| !v.is_finite()) {
            return Err(Error::Data(format!(
                "the start iterate has {} values (finite ones needed), the problem {} unknowns",
                s.len(),
                model.n()
            )));
        }
    }
    let (method, choice) = match settings.method {
        Method::Auto => auto_choice(model, hierarchy),
        m => (m, Choice::Requested),
    };
    let (mut solution, mut status, mut message) =
        run_method(method, model, hierarchy, built, settings, start, observer)?;
    let mut fallback = None;
    if settings.method == Method::Auto
        && method == Method::Multigrid
        && !status.is_accepted(settings)
    {
        fallback = Some(Fallback {
            from: method,
            status,
            residual: solution.certificate.kkt(),
            message: message.take(),
        });
        (solution, status, message) = run_method(
            Method::ActiveSet,
            model,
            hierarchy,
            built,
            settings,
            start,
            observer,
        )?;
    }
    Ok(Attempt {
        solution,
        status,
        requested: settings.method,
        choice,
        fallback,
        message,
    })
}

/// [`attempt`], for callers that need an accepted answer: any status the settings do not
/// accept ([`Status::is_accepted`]) is an [`Error::Solver`] naming it.
pub fn solve(
    model: &Model,
    hierarchy: Option<&Hierarchy>,
    settings: &Settings,
    observer: &mut dyn Observer,
) -> Result<Solution> {
    let a = attempt(model, hierarchy, settings, observer)?;
    if a.status.is_accepted(settings) {
        return Ok(a.solution);
    }
    Err(not_converged(&a, settings))
}

/// The error for an attempt that did not converge.
pub fn not_converged(a: &Attempt, settings: &Settings) -> Error {
    let s = &a.solution;
    status_error(
        a.status,
        s.method,
        s.iterations,
        s.certificate.kkt(),
        settings.tolerance,
        a.message.as_deref(),
    )
}

/// The error that names how a solve by `method` ended short of the tolerance.
pub fn status_error(
    status: Status,
    method: Method,
    iterations: usize,
    kkt: f64,
    tolerance: f64,
    message: Option<&str>,
) -> Error {
    let what = match status {
        Status::Converged => "converged".to_string(),
        Status::RoundingFloor => format!(
            "stopped at the rounding floor of double precision after {iterations} iterations"
        ),
        Status::IterationLimit => format!("reached the iteration limit ({iterations})"),
        Status::Stalled => format!("stalled after {iterations} iterations"),
        Status::NumericalFailure => "failed numerically".to_string(),
    };
    let why = message.map(|m| format!(" ({m})")).unwrap_or_default();
    Error::Solver {
        solver: method.name().into(),
        message: format!(
            "{what}, with scaled KKT residual {kkt:.3e} above the tolerance {tolerance:.1e}{why}"
        ),
    }
}

/// The memory a solve by `method` adds to the run's ([`crate::limits::run_bytes`]) on `unknowns`
/// unknowns: a sparse factorisation for the direct methods, nothing that grows faster
/// than the run's own data for multigrid and coordinate descent.
pub fn solver_bytes(method: Method, unknowns: usize) -> f64 {
    let n = unknowns.max(2) as f64;
    match method {
        Method::ActiveSet | Method::Linear => {
            crate::limits::DIRECT_BYTES_PER_UNKNOWN_LOG * n * n.log2()
        }
        Method::Qp => crate::limits::QP_BYTES_PER_UNKNOWN_LOG * n * n.log2(),
        Method::Auto | Method::Multigrid | Method::Coordinate => 0.0,
    }
}

/// Refuses a solve by `method` of a model of `unknowns` unknowns when its factorisation
/// would not fit in the memory available now (the mesh and the model are already
/// allocated and so are not counted again).
pub fn check_solver_fits(method: Method, unknowns: usize) -> Result<()> {
    let need = solver_bytes(method, unknowns);
    if need == 0.0 {
        return Ok(());
    }
    let (available, source) = crate::limits::available_memory();
    if need > available as f64 {
        return Err(Error::Data(format!(
            "solver {}: its factorisation of {unknowns} unknowns needs about {} of memory, \
             more than the {} available ({source}): use method = \"multigrid\" (with \
             mesh.refine ≥ 2) or \"auto\", or a coarser mesh",
            method.name(),
            crate::limits::human_bytes(need),
            crate::limits::human_bytes(available as f64),
        )));
    }
    Ok(())
}

/// Solves `model` with `settings` (on `hierarchy`'s levels, those `built` beforehand when
/// given; from `start` when given) by the library's one policy ([`attempt_with_levels`]:
/// the method the settings name, or `auto`'s choice with its fallback), after the memory
/// check of its solver; an answer whose J or certificate is not finite is refused
/// ([`check_solution`]). Every run solves through it: one step,
/// the steps of a sweep, the adaptive loop, and each level of a convergence study.
pub(crate) fn solve_model(
    model: &Model,
    hierarchy: Option<&Hierarchy>,
    built: Option<&multigrid::Levels>,
    settings: &Settings,
    start: Option<&[f64]>,
    observer: &mut dyn Observer,
) -> Result<Attempt> {
    let method = match settings.method {
        Method::Auto => auto_choice(model, hierarchy).0,
        m => m,
    };
    check_solver_fits(method, model.n())?;
    let a = attempt_with_levels(model, hierarchy, built, settings, start, observer)?;
    check_solution(
        a.solution.energy,
        a.solution.certificate.kkt(),
        model.is_rigid(),
    )?;
    Ok(a)
}

/// Refuses a solve whose energy J(U) or certificate is not a finite number (`rigid`: an
/// iterate outside `U ≤ φ` has J = +∞ by definition and is refused by its certificate
/// instead).
pub fn check_solution(energy: f64, kkt: f64, rigid: bool) -> Result<()> {
    if energy.is_nan() || (energy.is_infinite() && !(rigid && energy > 0.0)) {
        return Err(Error::Data(format!(
            "the energy J(U) of the answer is {energy}: {}",
            crate::model::OVERFLOW_HINT
        )));
    }
    if kkt.is_nan() {
        return Err(Error::Data(format!(
            "the certificate of the answer is not a number: {}",
            crate::model::OVERFLOW_HINT
        )));
    }
    Ok(())
}

#[cfg(test)]
mod check_tests {
    use super::check_solution;

    #[test]
    fn non_finite_answers_are_refused_naming_them() {
        assert!(check_solution(1.0, 1e-12, false).is_ok());
        assert!(check_solution(f64::INFINITY, 1.0, true).is_ok());
        let e = check_solution(f64::NAN, 1e-12, false).unwrap_err();
        assert!(e.to_string().contains("energy J(U)"), "{e}");
        assert!(check_solution(f64::NEG_INFINITY, 1e-12, true).is_err());
        assert!(check_solution(1.0, f64::NAN, false).is_err());
    }
}

#[cfg(test)]
pub(crate) mod tests;
