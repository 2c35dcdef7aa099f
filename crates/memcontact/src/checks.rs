//! The checks of derived numbers, on every path from data to a written result: the data
//! where assembly does not sample it (on the boundary), the assembled model for overflow
//! (S, L, D, φₙ, ∫f and the size of J), and the results of a solve (J, the certificate,
//! the fields and totals). A non-finite number is a clear error naming the data that made
//! it, never a certificate of 0 or a `null` in `summary.json`.
//!
//! [`assemble`] is the one way to a checked model: the front door ([`crate::run`]), the
//! convergence studies and the load sweeps use it; a sweep step that scales a model is
//! checked again with [`check_model`].

use crate::error::{Error, Result};
use crate::field::Coefficient;
use crate::mesh::Mesh;
use crate::mesh::VertexTriangles;
use crate::model::{Extensions, FoundationMatrix, Model, ProblemData, Stiffness};
use crate::results::{NodalFields, Totals};
use crate::sparse::first_non_finite;

/// Assembles the model of `data` with the extensions `ext` on `mesh`
/// ([`Model::assemble_with`]) between the checks of the boundary data
/// ([`check_boundary_data`]) and of overflow ([`check_model`]).
pub fn assemble(mesh: &Mesh, data: &ProblemData, ext: &Extensions) -> Result<Model> {
    let (adj, boundary) = mesh.patches();
    assemble_on(mesh, &adj, &boundary, data, ext)
}

/// [`assemble`] given the mesh's vertex → triangles adjacency and its boundary vertices.
pub fn assemble_on(
    mesh: &Mesh,
    adj: &VertexTriangles,
    boundary: &[bool],
    data: &ProblemData,
    ext: &Extensions,
) -> Result<Model> {
    check_boundary_data_on(mesh, adj, boundary, data, ext)?;
    let model = Model::assemble_on(mesh, adj, boundary, data, ext)?;
    check_model(mesh, &model)?;
    Ok(model)
}

/// Checks the data where assembly does not sample it: f on the boundary vertices (a load
/// singular on the boundary, like `1/x` on x = 0, is refused), and, where a body is rigid
/// next to the fixed boundary, that it leaves room for the prescribed height g there
/// (`φ ≥ g` above, `φ_low ≤ g` below: otherwise no continuous solution exists).
pub fn check_boundary_data(mesh: &Mesh, data: &ProblemData, ext: &Extensions) -> Result<()> {
    let (adj, boundary) = mesh.patches();
    check_boundary_data_on(mesh, &adj, &boundary, data, ext)
}

/// [`check_boundary_data`] given the mesh's adjacency and boundary vertices.
fn check_boundary_data_on(
    mesh: &Mesh,
    adj: &VertexTriangles,
    boundary: &[bool],
    data: &ProblemData,
    ext: &Extensions,
) -> Result<()> {
    // Without boundary conditions of its own, the whole boundary is fixed at height 0.
    let given = match ext.boundary {
        Some(_) => Some(crate::model::fixed_heights_on(mesh, adj, boundary, ext)?),
        None => None,
    };
    let rigid_upper = |region: u32| {
        matches!(data.stiffness, Stiffness::Rigid) || ext.rigid_regions.contains(&region)
    };
    for (v, &on) in boundary.iter().enumerate() {
        if !on {
            continue;
        }
        let p = mesh.points[v];
        let (fixed, g) = given.as_ref().map_or((true, 0.0), |(f, g)| (f[v], g[v]));
        for &k in adj.of(v) {
            let region = mesh.regions[k as usize];
            let f = value(data.load, p, region);
            if !f.is_finite() {
                return Err(Error::Data(format!(
                    "membrane.load f is not finite on the boundary at ({}, {}) (f = {f}): the \
                     load must be bounded on the closed domain",
                    p[0], p[1]
                )));
            }
            if !fixed {
                continue;
            }
            if rigid_upper(region) {
                let phi = value(data.shape, p, region);
                if phi < g {
                    return Err(Error::Data(format!(
                        "obstacle.shape φ = {phi} at the boundary point ({}, {}) lies below \
                         the fixed boundary (u = {g} there): with a rigid obstacle (u ≤ φ) the \
                         problem has no continuous solution; raise φ to at least {g} on the \
                         boundary or give the obstacle a finite stiffness",
                        p[0], p[1]
                    )));
                }
            }
            if let Some(low) = &ext.lower {
                if matches!(low.stiffness, Stiffness::Rigid) || low.rigid_regions.contains(&region)
                {
                    let phi = value(low.shape, p, region);
                    if phi > g {
                        return Err(Error::Data(format!(
                            "lower.shape φ_low = {phi} at the boundary point ({}, {}) lies \
                             above the fixed boundary (u = {g} there): with a rigid body \
                             below (u ≥ φ_low) the problem has no continuous solution; lower \
                             φ_low to at most {g} on the boundary or give the body a finite \
                             stiffness",
                            p[0], p[1]
                        )));
                    }
                }
            }
        }
    }
    Ok(())
}

/// A coefficient's value at `p` in `region`.
fn value(c: &dyn Coefficient, p: [f64; 2], region: u32) -> f64 {
    c.on_region(region).unwrap_or_else(|| c.at(p, region))
}

/// Refuses a model whose matrices or data overflowed double precision, naming the data.
pub fn check_model(mesh: &Mesh, model: &Model) -> Result<()> {
    if !model.s.is_finite() {
        let smallest_area = (0..mesh.n_triangles())
            .map(|k| mesh.area(k).abs())
            .fold(f64::INFINITY, f64::min);
        return Err(Error::Data(format!(
            "the stiffness matrix S overflows double precision: tension t = {:e} on triangles \
             as small as {smallest_area:e} (S grows like t × edge² / area); rescale the \
             problem (units) so that t and the mesh are moderate",
            model.tension
        )));
    }
    if !matrix_finite(&model.l) {
        return Err(Error::Data(
            "the foundation matrix L = ∫h gᵢgⱼ overflows double precision: \
             obstacle.stiffness h is too large (use stiffness = \"rigid\" for a rigid body)"
                .into(),
        ));
    }
    if let Some(i) = first_non_finite(&model.phi) {
        let p = mesh.points[model.dofs.vertex[i] as usize];
        return Err(Error::Data(format!(
            "obstacle.shape φ is not finite at ({}, {})",
            p[0], p[1]
        )));
    }
    if let Some(low) = &model.lower {
        if !matrix_finite(&low.l) {
            return Err(Error::Data(
                "the foundation matrix of the body below overflows double precision: \
                 lower.stiffness is too large (use stiffness = \"rigid\" for a rigid body)"
                    .into(),
            ));
        }
        if let Some(i) = first_non_finite(&low.phi) {
            let p = mesh.points[model.dofs.vertex[i] as usize];
            return Err(Error::Data(format!(
                "lower.shape φ_low is not finite at ({}, {})",
                p[0], p[1]
            )));
        }
    }
    if let Some(i) = first_non_finite(&model.d) {
        let p = mesh.points[model.dofs.vertex[i] as usize];
        return Err(Error::Data(format!(
            "the nodal load D = ∫f gᵢ overflows double precision near ({}, {}): \
             membrane.load f is too large",
            p[0], p[1]
        )));
    }
    if !model.total_load.is_finite() {
        return Err(Error::Data(
            "the total load ∫f overflows double precision: membrane.load f is too large".into(),
        ));
    }
    // J = ½UᵀSU − UᵀD with U of the size D/S: the products must stay finite.
    let d_max = crate::sparse::norm_inf(&model.d);
    let s_min = model.s.diag().into_iter().fold(f64::INFINITY, f64::min);
    let u_size = d_max / s_min * (model.n() as f64).sqrt();
    if !(d_max * u_size * model.n() as f64).is_finite() {
        return Err(Error::Data(format!(
            "the energy J would overflow double precision: the nodal loads |D| reach \
             {d_max:.3e} against a stiffness of {s_min:.3e} (membrane.load is too large for the \
             tension); rescale the problem (units)"
        )));
    }
    Ok(())
}

/// Whether a foundation matrix holds finite numbers only.
fn matrix_finite(l: &FoundationMatrix) -> bool {
    match l {
        FoundationMatrix::Consistent(l) => l.is_finite(),
        FoundationMatrix::Lumped(d) => first_non_finite(d).is_none(),
        FoundationMatrix::Rigid => true,
    }
}

/// What overflowed, in terms of the data, for the messages of [`check_solution`] and
/// [`check_results`].
const OVERFLOW_HINT: &str = "the data's scales (tension t, load f, stiffness h, shape φ, \
                             mesh size) overflow double precision; rescale the problem \
                             (units)";

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
    use crate::field::Field;
    use crate::model::{Foundation, Sampling};

    #[test]
    fn loads_singular_on_the_boundary_and_rigid_bodies_below_it_are_refused() {
        let mesh = crate::solve::tests::square(4);
        let bind = |f: &str| {
            Field::parse(f)
                .unwrap()
                .bind_to_mesh("membrane.load", &mesh)
                .unwrap()
        };
        let (load, shape, h) = (bind("1/x"), bind("0.1"), bind("10"));
        let mut data = ProblemData {
            tension: 1.0,
            load: &load,
            shape: &shape,
            stiffness: Stiffness::Elastic(&h),
            foundation: Foundation::Consistent,
            sampling: Sampling::Nodal,
        };
        let e = assemble(&mesh, &data, &Extensions::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("boundary") && e.contains("membrane.load"), "{e}");
        let (one, below) = (bind("1"), bind("x - 0.5"));
        data.load = &one;
        data.shape = &below;
        data.stiffness = Stiffness::Rigid;
        let e = assemble(&mesh, &data, &Extensions::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("below the fixed boundary"), "{e}");
        data.stiffness = Stiffness::Elastic(&h);
        assert!(assemble(&mesh, &data, &Extensions::default()).is_ok());
    }

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
