//! [`Report`]: how a solve went, with its iterate.

use crate::certificate::Certificate;
use crate::discretization::Phase;
use crate::error::Error;
use crate::outcome::fields::{NodalFields, Totals};
use crate::solve::{self, Choice, Fallback, IterationRecord, Method, Solution, Status};

/// How a solve went, with its iterate: the status, the method used and why, iterations,
/// J, the certificates of 2e and 2f, the history and the phase times.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Report {
    /// How the solve ended.
    pub status: Status,
    /// The settings accept the outcome (converged, or at the rounding floor when allowed).
    pub accepted: bool,
    /// The method the settings asked for (maybe `auto`).
    pub requested: Method,
    /// The method that produced the iterate.
    pub method: Method,
    /// The kind of multigrid hierarchy it ran on (multigrid only).
    pub coarsening: Option<crate::solve::multigrid::Kind>,
    /// Why that method was used.
    pub choice: Choice,
    /// The method `auto` tried first and gave up on.
    pub fallback: Option<Fallback>,
    /// What went wrong, for a numerical failure.
    pub message: Option<String>,
    /// Iterations of the method that produced the iterate.
    pub iterations: usize,
    /// J(U) (Problem 2b).
    pub energy: f64,
    /// The scaled residuals of 2e and 2f at U.
    pub certificate: Certificate,
    /// The tolerance the certificate was held to.
    pub tolerance: f64,
    /// Energy and residual per iteration.
    pub history: Vec<IterationRecord>,
    /// `mesh`, `assembly`, `solve` wall-clock seconds.
    pub phases: Vec<Phase>,
    /// The solver's own phases (setup, factorisation, smoothing, ...).
    pub solver_phases: Vec<Phase>,
    /// U over the unknowns (the best iterate).
    #[serde(skip)]
    pub u: Vec<f64>,
    /// The solver's multipliers of 2e, when it computes them (the QP does).
    #[serde(skip)]
    pub multipliers: Option<solve::Multipliers>,
    /// The vertex fields and totals of `u` in the solver's numbering, derived and checked
    /// once when the solve ended (`None`: derived again from `u` when asked for).
    #[serde(skip)]
    pub derived: Option<std::sync::Arc<(NodalFields, Totals)>>,
}

impl Report {
    /// Seconds of phase `name` (0 when it did not run).
    pub fn seconds(&self, name: &str) -> f64 {
        self.phases
            .iter()
            .filter(|p| p.name == name)
            .map(|p| p.seconds)
            .sum()
    }

    /// The error naming how the solve ended, when the settings do not accept it.
    pub fn error(&self) -> Option<Error> {
        (!self.accepted).then(|| {
            solve::status_error(
                self.status,
                self.method,
                self.iterations,
                self.certificate.kkt(),
                self.tolerance,
                self.message.as_deref(),
            )
        })
    }

    /// The iterate as a [`Solution`] (for the functions that derive results from one).
    pub fn solution(&self) -> Solution {
        Solution {
            u: self.u.clone(),
            method: self.method,
            iterations: self.iterations,
            energy: self.energy,
            certificate: self.certificate,
            multipliers: self.multipliers.clone(),
            history: self.history.clone(),
            phases: self
                .solver_phases
                .iter()
                .map(|p| (p.name.clone(), p.seconds))
                .collect(),
            coarsening: self.coarsening,
        }
    }
}
