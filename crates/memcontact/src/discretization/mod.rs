//! The discretisation of a problem (SPEC §2): mesh levels, the renumbering for locality,
//! the data bound to the mesh, and the model S, L, D, φₙ, M assembled once. Solves and
//! sweeps reuse it.

mod binding;
mod case_checks;
mod discrete;
mod meshing;

pub use binding::{assemble_model, bind_and_check, BoundBody, BoundData};
pub use case_checks::{check_case_on_mesh, check_load_cases_on_mesh, check_profile_on_mesh};
pub use discrete::{Discretization, Phase};
pub use meshing::build_mesh;
