//! The library's front door: one [`run`] from a [`Problem`] and [`Settings`] to an
//! [`Outcome`]. Data flows one way:
//!
//! ```text
//! Problem ─► Discretization (mesh levels, data bound to regions, S, L, D, φₙ, M)
//!         ─► solve (method, auto policy, fallback) ─► Outcome (U, Status, Report)
//! ```
//!
//! Bad input is an `Err`; a numerical outcome (converged, iteration limit, stalled,
//! numerical failure) is a [`Status`] inside the [`Report`], always with the best iterate
//! and its certificate. The library prints nothing: progress reaches the caller through
//! the [`Observer`].

mod one;
mod sweep;

pub use one::run;
pub use sweep::{apply, check_on_mesh, run_sweep, run_sweep_on, step_discretization, step_model};
