//! What a step of the adaptive loop produced: the row of `adapt.csv`.

use crate::outcome::Outcome;
use serde::Serialize;

/// One solved step of the adaptive loop.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AdaptRow {
    /// 0 for the start mesh.
    pub step: usize,
    /// Vertices of the step's mesh.
    pub vertices: usize,
    /// Unknowns.
    pub unknowns: usize,
    /// The estimator η = (Σ η_T²)^½, in the energy norm's units.
    pub estimator: f64,
    /// J(U).
    pub energy: f64,
    /// Σ |Qᵢ|/3 over the vertices in contact.
    pub contact_area: f64,
    /// Iterations of the step's solve.
    pub iterations: usize,
    /// The scaled KKT residual.
    pub kkt_residual: f64,
    /// Seconds of the step (refinement, assembly, solve, estimate).
    pub seconds: f64,
}

impl AdaptRow {
    /// The row of step `step`, solved as `outcome` with estimator `estimator` in
    /// `seconds`.
    pub fn of(step: usize, outcome: &Outcome, estimator: f64, seconds: f64) -> AdaptRow {
        let q = &outcome.discretization.quality;
        let r = &outcome.report;
        AdaptRow {
            step,
            vertices: q.vertices,
            unknowns: outcome.discretization.model.n(),
            estimator,
            energy: r.energy,
            contact_area: outcome.totals().contact_area,
            iterations: r.iterations,
            kkt_residual: r.certificate.kkt(),
            seconds,
        }
    }

    /// The header of `adapt.csv`.
    pub const HEADER: [&'static str; 9] = [
        "step",
        "vertices",
        "unknowns",
        "estimator",
        "energy",
        "contact_area",
        "iterations",
        "kkt_residual",
        "seconds",
    ];
}
