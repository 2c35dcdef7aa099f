//! The discretisation of a problem (docs/theory.md#discrete-model): mesh levels, the
//! renumbering for locality, the data bound to the mesh, and the model S, L, D, φₙ, M
//! assembled once. Solves and sweeps reuse it.

mod binding;
pub(crate) mod case_checks;
mod discrete;
mod meshing;
#[cfg(test)]
mod ordering_tests;

pub(crate) use binding::{assemble_model, bind_and_check, bind_height, BoundData};
pub(crate) use case_checks::check_case_on_mesh;
pub use discrete::{Discretization, Phase};
pub(crate) use meshing::build_mesh;
