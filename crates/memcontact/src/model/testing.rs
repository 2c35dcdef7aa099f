//! Small models for the tests of the layers above (certificates, solvers, multigrid).

use super::data::{BodyStiffness, Foundation, ProblemData, Sampling};
use super::system::Model;
use crate::field::FnCoefficient;
use crate::mesh::Mesh;

/// A model on `mesh`: t = 1, f = 8, φ = 0.12 + 0.05 sin(6x) y, the stiffness `h` (`None`:
/// rigid).
pub(crate) fn model(
    mesh: &Mesh,
    h: Option<&dyn crate::field::Coefficient>,
    foundation: Foundation,
) -> Model {
    let phi = FnCoefficient(|p: [f64; 2]| 0.12 + 0.05 * (6.0 * p[0]).sin() * p[1]);
    Model::assemble(
        mesh,
        &ProblemData {
            tension: 1.0,
            load: &8.0,
            shape: &phi,
            stiffness: match h {
                Some(h) => BodyStiffness::Elastic(h),
                None => BodyStiffness::Rigid,
            },
            foundation,
            sampling: Sampling::Nodal,
        },
    )
    .unwrap()
}
