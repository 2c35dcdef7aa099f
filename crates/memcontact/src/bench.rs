//! The building blocks of a solve, for the benchmark harness (`memcontact bench`,
//! `cargo bench`) that times them one by one: the P1 assembly kernels, the model's
//! assembly from raw data, the multigrid solver with its options and the timings of its
//! kernels, and the vertex numbering. Behind the `bench` feature; not a stable API (the
//! runs of [`mod@crate::run`] are the library's interface).

pub use crate::fem::{assemble_stiffness_and_mass, assemble_vector, unknowns_pattern};
pub use crate::mesh::reorder::edge_span;
pub use crate::mesh::{DofMap, VertexTriangles};
pub use crate::model::{BodyStiffness, Model, ProblemData};
pub use crate::sensitivity::outputs::locate;
pub use crate::solve::multigrid::{
    kernel_timings, poisson_solve, solve_with, Coarsening, TnnmgOptions,
};
pub use crate::write::write_parts_seconds;
