//! The checks of a solve's answer before anything is written: J and the certificate, the
//! fields and the totals must be finite numbers.

use crate::error::{Error, Result};
use crate::mesh::Mesh;
use crate::model::OVERFLOW_HINT;
use crate::outcome::fields::{NodalFields, Totals};
use crate::sparse::first_non_finite;

/// Refuses result fields or totals that are not finite numbers, naming the quantity and,
/// for a field, the vertex. Called before any result file is written.
pub fn check_results(mesh: &Mesh, fields: &NodalFields, totals: &Totals) -> Result<()> {
    let vertex_fields: [(&str, &[f64]); 4] = [
        ("the deflection u", &fields.u),
        ("the contact pressure", &fields.pressure),
        ("the contact force X₁", &fields.contact_force),
        ("the penetration", &fields.penetration),
    ];
    for (name, values) in vertex_fields {
        if let Some(v) = first_non_finite(values) {
            let p = mesh.points[v];
            return Err(Error::Data(format!(
                "{name} is {} at the vertex ({}, {}): {OVERFLOW_HINT}",
                values[v], p[0], p[1]
            )));
        }
    }
    let scalars = [
        ("the total load ∫f", totals.total_load),
        ("the total contact force", totals.total_contact_force),
        ("the contact area", totals.contact_area),
        ("the lift-off area", totals.liftoff_area),
        ("the largest pressure", totals.max_pressure),
        ("the largest deflection", totals.max_deflection),
    ];
    for (name, v) in scalars {
        if !v.is_finite() {
            return Err(Error::Data(format!("{name} is {v}: {OVERFLOW_HINT}")));
        }
    }
    Ok(())
}
