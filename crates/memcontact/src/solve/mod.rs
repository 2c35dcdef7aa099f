//! Solvers of the discrete problem, each a real implementation of one of the paper's
//! equivalent formulations, all on the same [`Model`]:
//!
//! | method | formulation |
//! | --- | --- |
//! | [`Method::Linear`] | h ≡ 0: one sparse Cholesky solve of `S U = D` |
//! | [`Method::ActiveSet`] | Problem 2f: semismooth (truncated) Newton with three vertex states |
//! | [`Method::Qp`] | Problem 2c handed to the Clarabel interior-point solver (multipliers of 2d/2e) |
//! | [`Method::Coordinate`] | Problem 2b: exact coordinatewise minimisation of J (SPEC §3) |
//! | [`Method::Multigrid`] | Problem 2b: truncated nonsmooth Newton multigrid |
//!
//! Every solve ends with the certificates of 2e and 2f; not reaching the tolerance is an
//! error, never a silently returned iterate.

pub mod active_set;
pub mod coordinate;
pub mod line_search;
pub mod linear;
pub mod local;
pub mod multigrid;
pub mod qp;

use crate::mesh::refine::Hierarchy;
use crate::model::{Certificate, Model};
use crate::{Error, Result};
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

/// Solver settings.
#[derive(Debug, Clone)]
pub struct Settings {
    /// The method.
    pub method: Method,
    /// Stop when the scaled KKT residual (max of 2e and 2f) is at most this.
    pub tolerance: f64,
    /// Iteration limit (`None`: the method's default).
    pub max_iterations: Option<usize>,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            method: Method::Auto,
            tolerance: 1e-10,
            max_iterations: None,
        }
    }
}

/// One line of a solver's history.
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct IterationRecord {
    /// Iteration number (1-based).
    pub iteration: usize,
    /// J after the iteration.
    pub energy: f64,
    /// The scaled KKT residual after the iteration (NaN when not computed).
    pub residual: f64,
}

/// Receives progress from a running solver (the CLI draws it; the library never prints).
pub trait Observer {
    /// Called after every iteration.
    fn iteration(&mut self, _record: &IterationRecord) {}
}

/// An observer that ignores everything.
pub struct Silent;
impl Observer for Silent {}

/// Multipliers of the Kuhn-Tucker system 2e, over the vertices of M (zero elsewhere).
#[derive(Debug, Clone)]
pub struct Multipliers {
    /// X₁: the contact forces the obstacle exerts.
    pub x1: Vec<f64>,
    /// X₂: the multipliers of `U₂ ≥ 0`.
    pub x2: Vec<f64>,
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

/// The method `auto` picks: linear when L = 0, multigrid when the mesh has a hierarchy,
/// the active-set method otherwise.
pub fn auto_method(model: &Model, hierarchy: Option<&Hierarchy>) -> Method {
    if model.is_linear() {
        Method::Linear
    } else if hierarchy.is_some_and(|h| h.depth() >= 3) {
        Method::Multigrid
    } else {
        Method::ActiveSet
    }
}

/// Solves the model with the chosen method. `hierarchy`, when given, must end with the
/// mesh the model was assembled on (multigrid uses its coarser levels).
pub fn solve(
    model: &Model,
    hierarchy: Option<&Hierarchy>,
    settings: &Settings,
    observer: &mut dyn Observer,
) -> Result<Solution> {
    if !(settings.tolerance.is_finite() && settings.tolerance > 0.0) {
        return Err(Error::Data(format!(
            "solver.tolerance must be a finite number > 0, got {}",
            settings.tolerance
        )));
    }
    let method = match settings.method {
        Method::Auto => auto_method(model, hierarchy),
        m => m,
    };
    let solution = match method {
        Method::Linear => linear::solve(model, settings)?,
        Method::ActiveSet => active_set::solve(model, settings, observer)?,
        Method::Qp => qp::solve(model, settings)?,
        Method::Coordinate => coordinate::solve(model, settings, observer)?,
        Method::Multigrid => {
            let h = hierarchy.ok_or_else(|| Error::Solver {
                solver: "multigrid".into(),
                message: "the mesh has no refinement hierarchy: set mesh.refine > 0, use the \
                          rectangle generator with nx, ny divisible by a power of two, or \
                          choose method = \"active-set\""
                    .into(),
            })?;
            match multigrid::solve(model, h, settings, observer) {
                // `auto` chose multigrid: if it cannot reach the tolerance, the exact
                // active-set method (with a direct solver) is the robust fallback.
                Ok(s)
                    if settings.method == Method::Auto
                        && (s.certificate.kkt().is_nan()
                            || s.certificate.kkt() > settings.tolerance) =>
                {
                    active_set::solve(model, settings, observer)?
                }
                Err(_) if settings.method == Method::Auto => {
                    active_set::solve(model, settings, observer)?
                }
                other => other?,
            }
        }
        Method::Auto => unreachable!("resolved above"),
    };
    let kkt = solution.certificate.kkt();
    if kkt.is_nan() || kkt > settings.tolerance {
        return Err(Error::Solver {
            solver: method.name().into(),
            message: format!(
                "stopped after {} iterations with scaled KKT residual {kkt:.3e} above the \
                 tolerance {:.1e}",
                solution.iterations, settings.tolerance
            ),
        });
    }
    Ok(solution)
}

#[cfg(test)]
pub(crate) mod tests;
