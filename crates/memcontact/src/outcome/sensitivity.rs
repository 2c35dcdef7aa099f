//! The sensitivity run's totals in `summary.json` (beside the solve's values): the biactive
//! vertices, how the derivatives were computed, and every linear solve with its residual
//! and time (docs/theory.md#sensitivities).

use crate::sensitivity::{Sensitivities, SolveRecord};

/// The keys `[sensitivity]` adds to `summary.json`.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SensitivityTotals {
    /// Biactive vertices (on a body's surface with a contact force at an end of its
    /// range, to the certificate's accuracy): where there are any, the rows they reach
    /// give both one-sided derivatives.
    pub sensitivity_biactive: usize,
    /// `adjoint` (one solve per output), `tangent` (one per parameter) or `one_sided`.
    pub sensitivity_mode: String,
    /// The linear solver: `cholesky` or `multigrid-cg` (none when no solve was needed).
    pub sensitivity_solver: String,
    /// Linear solves done.
    pub sensitivity_solves: usize,
    /// The largest relative residual `‖b − K x‖∞ / ‖b‖∞` of those solves.
    pub sensitivity_max_residual: f64,
    /// Seconds of the linear solves (factorisation or multigrid setup included).
    pub sensitivity_solve_seconds: f64,
    /// Seconds of the whole analysis.
    pub sensitivity_seconds: f64,
    /// The force accuracy the index sets were judged with (10 × the certificate's residual
    /// times its force scale).
    pub sensitivity_force_tolerance: f64,
    /// Every solve: what (`adjoint:OUTPUT`, `tangent:KEY`, `tangent+:KEY`, ...), solver,
    /// iterations, residual and seconds.
    pub sensitivity_solve_records: Vec<SolveRecord>,
}

impl SensitivityTotals {
    /// The totals of `s`.
    pub fn of(s: &Sensitivities) -> SensitivityTotals {
        SensitivityTotals {
            sensitivity_biactive: s.biactive(),
            sensitivity_mode: s.mode.name().into(),
            sensitivity_solver: s
                .solves
                .first()
                .map_or_else(|| "none".into(), |r| r.solver.clone()),
            sensitivity_solves: s.solves.len(),
            sensitivity_max_residual: s.solves.iter().map(|r| r.residual).fold(0.0, f64::max),
            sensitivity_solve_seconds: s.solves.iter().map(|r| r.seconds).sum(),
            sensitivity_seconds: s.seconds,
            sensitivity_force_tolerance: s.force_tolerance,
            sensitivity_solve_records: s.solves.clone(),
        }
    }
}
