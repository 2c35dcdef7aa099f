//! The discretisation of a problem (SPEC §2): mesh levels, the renumbering for locality,
//! the data bound to the mesh, and the model S, L, D, φₙ, M assembled once. Solves and
//! sweeps reuse it.

mod binding;
mod discrete;
mod meshing;

pub(crate) use binding::bind_height;
pub use binding::{assemble_model, bind_and_check, BoundBody, BoundData};
pub use discrete::{Discretization, Phase};
pub use meshing::build_mesh;
