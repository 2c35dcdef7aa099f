//! What a step of a sweep or a load case produced: the row of `sweep.csv`.

use super::solved::Outcome;
use crate::case::StepSpec;
use serde::Serialize;

/// What a step produced, for `sweep.csv`.
#[derive(Debug, Clone, Serialize)]
pub struct StepRow {
    /// 0-based index.
    pub step: usize,
    /// `step-000` or the load case's name.
    pub name: String,
    /// The swept value (a load case's load factor).
    pub value: f64,
    /// max |u|.
    pub max_deflection: f64,
    /// Σ |Qᵢ|/3 over the vertices in contact.
    pub contact_area: f64,
    /// Area covered by the body where the membrane is clear of it.
    pub liftoff_area: f64,
    /// Σ X₁.
    pub total_contact_force: f64,
    /// The largest contact pressure.
    pub max_pressure: f64,
    /// J(U).
    pub energy: f64,
    /// Iterations of the solve.
    pub iterations: usize,
    /// The scaled KKT residual.
    pub kkt_residual: f64,
    /// Seconds of the step (assembly when needed, and the solve).
    pub seconds: f64,
}

impl StepRow {
    /// The row of `step`, solved as `outcome` in `seconds`.
    pub fn of(step: &StepSpec, outcome: &Outcome, seconds: f64) -> StepRow {
        let t = outcome.totals();
        let r = &outcome.report;
        StepRow {
            step: step.index,
            name: step.name.clone(),
            value: step.value,
            max_deflection: t.max_deflection,
            contact_area: t.contact_area,
            liftoff_area: t.liftoff_area,
            total_contact_force: t.total_contact_force,
            max_pressure: t.max_pressure,
            energy: r.energy,
            iterations: r.iterations,
            kkt_residual: r.certificate.kkt(),
            seconds,
        }
    }

    /// The header of `sweep.csv`.
    pub const HEADER: [&'static str; 12] = [
        "step",
        "name",
        "value",
        "max_deflection",
        "contact_area",
        "liftoff_area",
        "total_contact_force",
        "max_pressure",
        "energy",
        "iterations",
        "kkt_residual",
        "seconds",
    ];
}
