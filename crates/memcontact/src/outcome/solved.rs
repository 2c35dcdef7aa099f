//! [`Outcome`]: a solved discretisation, with the fields and totals of its answer in the
//! user's numbering.

use super::fields::{derive_from, LowerFields, NodalFields, Totals};
use super::report::Report;
use crate::discretization::Discretization;
use crate::error::Result;
use crate::mesh::Mesh;
use crate::solve::Status;
use std::borrow::Cow;

/// What [`crate::run::run`] produced: the discretisation and the report with the iterate.
#[derive(Debug, Clone)]
pub struct Outcome {
    /// Mesh levels and model.
    pub discretization: Discretization,
    /// Status, method, certificate, history, times, and U.
    pub report: Report,
}

impl Outcome {
    /// How the solve ended.
    pub fn status(&self) -> Status {
        self.report.status
    }

    /// The solved mesh in the user's numbering (the numbering of every output).
    pub fn mesh(&self) -> std::borrow::Cow<'_, Mesh> {
        self.discretization.mesh().in_user_numbering()
    }

    /// The vertex fields (u, φ, penetration, pressure, contact forces, states) in the
    /// user's vertex numbering, and the totals.
    pub fn fields(&self) -> (Cow<'_, NodalFields>, Totals) {
        let (fields, totals) = self.solver_fields();
        (self.to_user(fields), totals)
    }

    /// The totals of the answer (load, reaction, contact area, ...).
    pub fn totals(&self) -> Totals {
        self.solver_fields().1
    }

    /// [`Outcome::fields`], checked to be finite (a field or a total that is not is refused,
    /// naming the quantity and, for a field, the vertex): the fields that result files hold.
    pub fn checked_fields(&self) -> Result<(Cow<'_, NodalFields>, Totals)> {
        let (fields, totals) = self.solver_fields();
        crate::outcome::checks::check_results(self.discretization.mesh(), &fields, &totals)?;
        Ok((self.to_user(fields), totals))
    }

    /// The fields and totals in the solver's numbering: those of the report, or derived
    /// from its `u` when it has none.
    pub(crate) fn solver_fields(&self) -> (Cow<'_, NodalFields>, Totals) {
        match &self.report.derived {
            Some(d) => (Cow::Borrowed(&d.0), d.1),
            None => {
                let d = &self.discretization;
                let (f, totals) = derive_from(d.mesh(), &d.model, &self.report.u);
                (Cow::Owned(f), totals)
            }
        }
    }

    /// Vertex fields in the solver's numbering mapped to the user's.
    fn to_user<'a>(&self, f: Cow<'a, NodalFields>) -> Cow<'a, NodalFields> {
        let mesh = self.discretization.mesh();
        if mesh.numbering.is_none() {
            return f;
        }
        let user = |x: &[f64]| mesh.vertex_values_to_user(x);
        Cow::Owned(NodalFields {
            u: user(&f.u),
            phi: user(&f.phi),
            penetration: user(&f.penetration),
            pressure: user(&f.pressure),
            contact_force: user(&f.contact_force),
            state: mesh.vertex_values_to_user(&f.state),
            covered: mesh.vertex_values_to_user(&f.covered),
            lower: f.lower.as_ref().map(|l| LowerFields {
                phi: user(&l.phi),
                penetration: user(&l.penetration),
                pressure: user(&l.pressure),
                contact_force: user(&l.contact_force),
                state: mesh.vertex_values_to_user(&l.state),
                covered: mesh.vertex_values_to_user(&l.covered),
            }),
        })
    }
}
