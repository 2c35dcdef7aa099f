//! The checks of a solve's answer before anything is written: J and the certificate, the
//! fields and the totals must be finite numbers.

use crate::error::{Error, Result};
use crate::mesh::Mesh;
use crate::model::OVERFLOW_HINT;
use crate::outcome::fields::{NodalFields, Totals};
use crate::sparse::first_non_finite;

/// Refuses a solve whose energy J(U) or certificate is not a finite number (`rigid`: an
/// iterate outside `U ≤ φ` has J = +∞ by definition and is refused by its certificate
/// instead).
pub fn check_solution(energy: f64, kkt: f64, rigid: bool) -> Result<()> {
    if energy.is_nan() || (energy.is_infinite() && !(rigid && energy > 0.0)) {
        return Err(Error::Data(format!(
            "the energy J(U) of the answer is {energy}: {OVERFLOW_HINT}"
        )));
    }
    if kkt.is_nan() {
        return Err(Error::Data(format!(
            "the certificate of the answer is not a number: {OVERFLOW_HINT}"
        )));
    }
    Ok(())
}

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

#[cfg(test)]
mod tests {
    use super::*;

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
