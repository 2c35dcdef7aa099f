//! The library's front door, and the only places that run: [`run`] (a case of one step),
//! [`run_sweep`] (its steps in turn), [`crate::verify::study::run_study`] (a convergence
//! study), [`run_sensitivity`] (a case's derivatives) and [`run_fit`] (its parameters
//! fitted to measurements), each from a [`crate::case::Case`] to owned outcomes that the writers of
//! [`crate::write`] store. Data flows one way:
//!
//! ```text
//! Problem ─► Discretization (mesh levels, data bound to regions, S, L, D, φₙ, M)
//!         ─► solve (method, auto policy, fallback) ─► Outcome (U, Status, Report)
//! ```
//!
//! Bad input is an `Err`; a numerical outcome (converged, iteration limit, stalled,
//! numerical failure) is a [`crate::solve::Status`] inside the [`crate::outcome::Report`], always with the best iterate
//! and its certificate. The library prints nothing: progress reaches the caller through
//! the [`crate::solve::Observer`].

mod fit;
mod one;
mod sensitivity;
mod sweep;

pub use crate::adapt::{check_adapt_on_mesh, run_adapt, AdaptRun, AdaptStop, OnStep};
pub use crate::verify::study::{run_study, StudyOptions, StudyOutcome};
pub use fit::{run_fit, FitProblem, FitRun};
pub use one::{check, run, run_to_files, Checked, Written};
pub use sensitivity::{run_request, run_sensitivity, SensitivityRun};
pub use sweep::{apply, run_sweep, run_sweep_on, step_discretization, step_model, SweepRun};
